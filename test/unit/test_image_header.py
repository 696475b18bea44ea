"""A compressed frame's size read from its header alone (vision/image_header.py), against
what OpenCV decodes, on random sizes and headers."""

import struct
import zlib

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from server_select.vision.image_codec import ImageError, decode, encode
from server_select.vision.image_header import HeaderError, PNG_SIGNATURE, dimensions

SIDES = st.integers(min_value=1, max_value=65535)


def png_header(width, height):
    ihdr = struct.pack('>IIBBBBB', width, height, 8, 0, 0, 0, 0)
    return PNG_SIGNATURE + struct.pack('>I', 13) + b'IHDR' + ihdr + \
        struct.pack('>I', zlib.crc32(b'IHDR' + ihdr))


def jpeg_header(width, height, segments=(), sof=0xC0, fill=0):
    """A JPEG's start: SOI, ``segments`` (marker, payload) before its SOF, the SOF."""
    out = b'\xff\xd8'
    for marker, payload in segments:
        out += b'\xff' * (1 + fill) + bytes([marker]) + struct.pack('>H', len(payload) + 2) \
            + payload
    body = struct.pack('>BHHB', 8, height, width, 1) + b'\x01\x11\x00'
    return out + b'\xff' + bytes([sof]) + struct.pack('>H', len(body) + 2) + body


@settings(deadline=None)     # (make test runs this beside other streams on 2 cores)
@given(SIDES, SIDES)
def test_a_png_header_says_its_size(width, height):
    assert dimensions(png_header(width, height) + b'\x00' * 10) == (width, height)


@settings(deadline=None)
@given(SIDES, SIDES, st.lists(st.tuples(st.sampled_from([0xE0, 0xE1, 0xDB, 0xC4, 0xFE]),
                                        st.binary(max_size=300)), max_size=4),
       st.sampled_from([0xC0, 0xC1, 0xC2, 0xC3, 0xC9, 0xCA]), st.integers(0, 2))
def test_a_jpeg_header_says_its_size_past_any_segments_before_its_frame(
        width, height, segments, sof, fill):
    assert dimensions(jpeg_header(width, height, segments, sof, fill)) == (width, height)


@settings(deadline=None)
@given(st.binary(max_size=200))
def test_any_other_bytes_are_refused_or_give_a_size_from_a_header(data):
    try:
        width, height = dimensions(data)
    except HeaderError:
        return
    assert data.startswith((PNG_SIGNATURE, b'\xff\xd8')) and width > 0 and height > 0


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 300), st.integers(1, 300), st.sampled_from(['jpeg', 'png']))
def test_the_header_says_what_opencv_decodes(width, height, kind):
    pixels = np.random.default_rng(width).integers(0, 255, (height, width, 3), dtype=np.uint8)
    fmt, data = encode(pixels, 80, kind)
    assert dimensions(data) == (width, height)
    assert decode(fmt, data).shape == (height, width, 3)


def test_a_jpeg_with_large_segments_before_its_frame_says_its_size():
    """A camera's EXIF thumbnail and ICC profile: several 64 KB segments before the frame."""
    segments = [(0xE1, bytes(65000)), (0xE2, bytes(65000)), (0xE2, bytes(65000))]
    assert dimensions(jpeg_header(4000, 3000, segments)) == (4000, 3000)


@pytest.mark.parametrize('data, why', [
    (b'\x89PNG\r\n\x1a\n' + b'\x00' * 8, 'without its IHDR'),
    (jpeg_header(0, 480), '0 x 480'),
    (b'\xff\xd8\xff\xda\x00\x02', 'without its start of frame'),
    (b'GIF89a', 'neither a PNG nor a JPEG'),
])
def test_headers_that_do_not_say_a_size_are_named(data, why):
    with pytest.raises(HeaderError, match=why):
        dimensions(data)


def test_a_png_bomb_is_refused_from_its_header_before_it_is_inflated():
    """About 30 KB of PNG that would inflate to 30000 x 30000 pixels (900 MB)."""
    bomb = png_header(30000, 30000) + b'\x00\x00\x00\x00IDAT' + zlib.compress(b'\x00' * 1000)
    with pytest.raises(ImageError, match='30000x30000 exceeds max_image_pixels'):
        decode('png', bomb)
