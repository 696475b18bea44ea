"""Image conversion and detection on real photographs shipped in scikit-image's wheel."""
import threading

import cv2
import numpy as np
import pytest

from server_select.vision.detection import Detector, DetectorError, annotate, iou
from server_select.vision.image_codec import ImageError, from_array, to_array
from server_select.vision.search import sample_image

FACE = (177, 66, 95, 95)   # where the astronaut's face is in astronaut.png (x, y, w, h)


@pytest.fixture(scope='module')
def astronaut():
    return sample_image('astronaut.png')


@pytest.fixture(scope='module')
def detector():
    return Detector()


def as_message(bgr, encoding, padding=0):
    """Fields of a sensor_msgs/Image in ``encoding``, rows padded by ``padding`` bytes."""
    encoding, height, width, step, data = from_array(
        bgr if encoding != 'mono8' else cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY), encoding)
    if padding:
        rows = np.frombuffer(data, np.uint8).reshape(height, step)
        rows = np.hstack([rows, np.full((height, padding), 7, np.uint8)])
        step, data = step + padding, rows.tobytes()
    return encoding, height, width, step, data


def test_round_trip_of_every_encoding_with_and_without_padding(astronaut):
    gray = cv2.cvtColor(astronaut, cv2.COLOR_BGR2GRAY)
    for encoding in ('bgr8', 'rgb8', 'mono8'):
        for padding in (0, 5):
            fields = as_message(astronaut, encoding, padding)
            back = to_array(*fields)
            assert np.array_equal(back, gray if encoding == 'mono8' else astronaut)


def test_rgb8_really_is_rgb():
    pixel = np.array([[[255, 0, 0]]], dtype=np.uint8)       # BGR: blue
    encoding, h, w, step, data = from_array(pixel, 'rgb8')
    assert data == bytes([0, 0, 255])                        # RGB order in the message
    assert to_array(encoding, h, w, step, data).tolist() == [[[255, 0, 0]]]


@pytest.mark.parametrize('fields, message', [
    (('bgra8', 2, 2, 8, bytes(16)), 'unsupported encoding'),
    (('16UC1', 2, 2, 4, bytes(8)), 'unsupported encoding'),
    (('bgr8', 2, 2, 6, bytes(11)), 'expected step x height'),
    (('bgr8', 2, 2, 5, bytes(10)), 'step 5 is smaller'),
    (('mono8', 0, 2, 2, b''), 'empty image'),
])
def test_bad_images_are_refused_with_the_reason(fields, message):
    with pytest.raises(ImageError, match=message):
        to_array(*fields)


def test_face_is_found_where_it_is(astronaut, detector):
    boxes = detector.detect(astronaut)
    assert len(boxes) == 1
    assert boxes[0].label == 'face'
    assert iou(boxes[0][:4], FACE) > 0.5


@pytest.mark.parametrize('name', ['camera.png', 'coffee.png', 'chelsea.png'])
def test_photos_without_a_face_give_nothing(name, detector):
    assert detector.detect(sample_image(name)) == []


def test_every_encoding_and_padding_gives_the_same_boxes(astronaut, detector):
    reference = [b[:4] for b in detector.detect(astronaut)]
    for encoding in ('bgr8', 'rgb8', 'mono8'):
        for padding in (0, 3):
            frame = to_array(*as_message(astronaut, encoding, padding))
            assert [b[:4] for b in detector.detect(frame)] == reference, (encoding, padding)


def test_annotate_draws_boxes_on_a_copy(astronaut, detector):
    boxes = detector.detect(astronaut)
    drawn = annotate(astronaut, boxes)
    assert drawn.shape == astronaut.shape and not np.array_equal(drawn, astronaut)
    assert annotate(astronaut[:, :, 0], []).shape == astronaut.shape


def test_hog_and_bad_configurations():
    assert Detector(kind='hog').label == 'person'
    assert Detector(cascade='haarcascade_fullbody.xml').label == 'fullbody'
    with pytest.raises(DetectorError, match='no cascade'):
        Detector(cascade='haarcascade_unicorn.xml')
    with pytest.raises(DetectorError, match='unknown detector'):
        Detector(kind='yolo')


def test_iou():
    assert iou((0, 0, 10, 10), (0, 0, 10, 10)) == 1.0
    assert iou((0, 0, 10, 10), (20, 20, 5, 5)) == 0.0
    assert iou((0, 0, 10, 10), (5, 0, 10, 10)) == pytest.approx(1 / 3.0)


@pytest.mark.parametrize('kind', ['haar', 'hog'])
def test_frames_searched_at_once_keep_their_own_boxes(astronaut, kind):
    """A server searches the frames of several robots in several threads with one detector."""
    detector = Detector(kind=kind)
    frames = [astronaut, np.full_like(astronaut, 100)]
    expected = [detector.detect(f) for f in frames]
    assert expected[0] != expected[1]
    wrong = []

    def search(index):
        for _ in range(40 if kind == 'haar' else 5):
            boxes = detector.detect(frames[index])
            if boxes != expected[index]:
                wrong.append((index, boxes))

    threads = [threading.Thread(target=search, args=(i,)) for i in (0, 1)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not wrong, wrong[:3]


def test_a_detector_built_not_loaded_finds_the_same_and_checks_its_cascade_at_once(astronaut):
    loaded, deferred = Detector(), Detector(load=False)
    assert deferred.classifier is None                    # no OpenCV classifier yet
    assert deferred.detect(astronaut) == loaded.detect(astronaut) != []
    assert deferred.classifier is not None
    with pytest.raises(DetectorError, match='no cascade'):
        Detector(cascade='haarcascade_nothing.xml', load=False)
