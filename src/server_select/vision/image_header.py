"""A compressed frame's size from its header alone (no decoder, no rospy): PNG's IHDR
chunk, JPEG's start-of-frame segment. A frame is checked against the pixel budget from
these before any byte of it is decoded: a PNG of 1 MB can decode to 30000 x 30000
pixels, and a decoder asked for a reduced image still inflates all of it.
"""

import struct

PNG_SIGNATURE = b'\x89PNG\r\n\x1a\n'
JPEG_START = b'\xff\xd8'
# start-of-frame markers (baseline, extended, progressive, lossless; Huffman or arithmetic)
SOF_MARKERS = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}
STANDALONE = frozenset(range(0xD0, 0xD8)) | {0x01}    # restart markers, TEM: no length
START_OF_SCAN = 0xDA
HEADER_BYTES = 1 << 20      # a JPEG's segments before its frame (EXIF, ICC profiles) fit


class HeaderError(ValueError):
    """A frame whose header does not say its size; the message says why."""


def dimensions(data):
    """``(width, height)`` of the PNG or JPEG frame in the bytes ``data``, read from its
    header (HeaderError: neither, or a header cut short or malformed)."""
    data = bytes(data[:HEADER_BYTES])
    if data.startswith(PNG_SIGNATURE):
        width, height = _png(data)
    elif data.startswith(JPEG_START):
        width, height = _jpeg(data)
    else:
        raise HeaderError('neither a PNG nor a JPEG header')
    if not width or not height:       # (a JPEG's height may come later: not taken)
        raise HeaderError('a header of %d x %d pixels' % (width, height))
    return width, height


def _png(data):
    if len(data) < 24 or data[12:16] != b'IHDR':
        raise HeaderError('a PNG without its IHDR chunk first')
    width, height = struct.unpack('>II', data[16:24])
    return width, height


def _jpeg(data):
    at = 2
    while at + 4 <= len(data):
        if data[at] != 0xFF:
            raise HeaderError('a JPEG segment without its marker at byte %d' % at)
        marker = data[at + 1]
        if marker == 0xFF:              # a fill byte before the marker
            at += 1
            continue
        if marker in STANDALONE:
            at += 2
            continue
        if marker == START_OF_SCAN:
            break
        length = struct.unpack('>H', data[at + 2:at + 4])[0]
        if length < 2:
            raise HeaderError('a JPEG segment of length %d at byte %d' % (length, at))
        if marker in SOF_MARKERS:
            if at + 9 > len(data):
                break
            height, width = struct.unpack('>HH', data[at + 5:at + 9])
            return width, height
        at += 2 + length
    raise HeaderError('a JPEG without its start of frame in the first %d bytes' % len(data))
