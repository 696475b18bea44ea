"""Compressed frames: what image_transport's compressed plugin sends, and detection on them."""

import numpy as np
import pytest

from server_select.vision.detection import Detector, iou, search_frame
from server_select.vision.image_codec import (ImageError, convert, decode, encode, from_array,
                                              task_frame)
from server_select.vision.search import sample_image


def test_jpeg_and_png_round_trip_with_image_transports_format():
    photo = sample_image('astronaut.png')
    fmt, data = encode(photo, 80)
    assert fmt == 'bgr8; jpeg compressed bgr8' and len(data) < photo.nbytes / 5
    back = decode(fmt, data)
    assert back.shape == photo.shape
    assert np.abs(back.astype(int) - photo.astype(int)).mean() < 6
    fmt, data = encode(convert(photo, 'mono8'), kind='png')
    assert fmt == 'mono8; png compressed mono8'
    assert (decode(fmt, data)[:, :, 0] == convert(photo, 'mono8')).all()   # lossless


def test_detection_is_the_same_on_jpeg_frames():
    detector = Detector()
    for name, faces in (('astronaut.png', 1), ('coffee.png', 0)):
        photo = sample_image(name)
        raw_boxes, _ = search_frame(detector, from_array(photo))
        jpeg_boxes, annotated = search_frame(detector, ('', 0, 0, 0, b''), encode(photo, 80))
        assert len(raw_boxes) == len(jpeg_boxes) == faces
        for a, b in zip(raw_boxes, jpeg_boxes):
            assert iou(a, b) > 0.9
        assert annotated.shape == photo.shape


@pytest.mark.parametrize('fmt, data, why', [
    ('jpeg', b'', 'empty compressed frame'),
    ('jpeg', b'not a jpeg at all', 'does not decode'),
    ('bgr8; theora compressed', b'x', 'unsupported compressed format'),
])
def test_bad_compressed_frames_are_refused_with_the_reason(fmt, data, why):
    with pytest.raises(ImageError) as info:
        decode(fmt, data)
    assert why in str(info.value)


def test_a_compressed_frame_larger_than_allowed_is_refused_before_it_is_decoded():
    fmt, data = encode(np.zeros((2000, 3000, 3), np.uint8), 50)     # small file, 6 Mpixel
    with pytest.raises(ImageError) as info:
        task_frame(('', 0, 0, 0, b''), (fmt, data), max_pixels=1 << 20)
    assert 'exceeds max_image_pixels' in str(info.value)
    assert task_frame(('', 0, 0, 0, b''), (fmt, data), max_pixels=1 << 23).shape == (2000, 3000, 3)
