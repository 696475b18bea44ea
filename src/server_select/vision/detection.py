"""Target detection in camera frames with OpenCV (no rospy): Haar cascades or HOG people."""

import collections
import importlib.util
import os
import threading

from server_select.core.settings import default
from server_select.core.util.lazy import deferred
from server_select.vision.image_codec import MAX_PIXELS, task_frame, to_gray

np = deferred('numpy')

Box = collections.namedtuple('Box', 'x y width height label score')

# Where Debian's opencv-data installs the cascades (its python3-opencv has no cv2.data).
DEBIAN_CASCADES = '/usr/share/opencv4/haarcascades'


class DetectorError(ValueError):
    """A detector configuration that cannot be used."""


def cascade_dir():
    """The folder of OpenCV's Haar cascades: ``cv2/data`` (pip wheels: ``cv2.data.
    haarcascades``, found without loading OpenCV) or Debian's opencv-data folder;
    DetectorError when neither exists."""
    spec = importlib.util.find_spec('cv2')
    wheel = os.path.join(os.path.dirname(spec.origin), 'data') \
        if spec is not None and spec.origin else None
    for folder in (wheel, DEBIAN_CASCADES):
        if folder and os.path.isfile(os.path.join(folder, 'haarcascade_frontalface_default.xml')):
            return folder
    raise DetectorError('no Haar cascades found: neither cv2.data.haarcascades nor %s '
                        '(Debian package opencv-data)' % DEBIAN_CASCADES)


def make_detector(param, load=True):
    """The detector the ``detector``, ``cascade``, ``scale_factor``, ``min_neighbors`` and
    ``min_size`` parameters describe; ``param(name)`` reads one (the server and a robot in
    local mode build theirs here, so both do the same work). ``load`` False: OpenCV with
    :meth:`Detector.load` or the first frame."""
    return Detector(kind=param('detector'), cascade=param('cascade'),
                    scale_factor=param('scale_factor'), min_neighbors=param('min_neighbors'),
                    min_size=param('min_size'), load=load)


class Detector(object):
    """``detect(frame)`` -> list of :class:`Box`.

    ``kind`` ``haar``: a cascade of :func:`cascade_dir` (by file name) or a path;
    ``kind`` ``hog``: OpenCV's default HOG people detector.

    Thread-safe: OpenCV keeps the image being searched inside the classifier, so two
    frames searched at once by one classifier (a server's callbacks run in one thread per
    robot connection) get each other's boxes; ``detect`` lets one frame in at a time.
    """

    def __init__(self, kind=default('detector'), cascade=default('cascade'),
                 scale_factor=default('scale_factor'), min_neighbors=default('min_neighbors'),
                 min_size=default('min_size'), label=None, load=True):
        """``load`` False: the parameters are checked now and OpenCV is loaded by
        :meth:`load` or with the first frame (a server that never gets one needs no
        OpenCV: 17 MiB)."""
        self.kind = kind
        self.scale_factor = float(scale_factor)
        self.min_neighbors = int(min_neighbors)
        self.min_size = int(min_size)
        self._lock = threading.Lock()
        self.classifier = self.hog = None
        if kind == 'haar':
            folder = None if os.path.isabs(cascade) else cascade_dir()
            self.path = path = os.path.join(folder, cascade) if folder else cascade
            if not os.path.isfile(path):
                available = sorted(f for f in os.listdir(folder or os.path.dirname(path))
                                   if f.endswith('.xml')) if folder else []
                raise DetectorError('no cascade %r (%s has: %s)'
                                    % (cascade, folder or 'path', ', '.join(available)))
            name = os.path.basename(path)[len('haarcascade_'):-len('.xml')] \
                if os.path.basename(path).startswith('haarcascade_') else 'target'
            self.label = label or ('face' if 'face' in name else name)
        elif kind == 'hog':
            self.label = label or 'person'
        else:
            raise DetectorError('unknown detector %r (expected haar or hog)' % kind)
        if load:
            self._load()

    def load(self):
        """Load OpenCV and the detector now (else with the first frame)."""
        with self._lock:
            self._load()

    def _load(self):
        """OpenCV's classifier (DetectorError when the cascade does not load)."""
        import cv2    # lazy: no OpenCV in a node that needs none
        if self.kind == 'haar' and self.classifier is None:
            classifier = cv2.CascadeClassifier(self.path)
            if classifier.empty():
                raise DetectorError('cannot load cascade %s' % self.path)
            self.classifier = classifier
        elif self.kind == 'hog' and self.hog is None:
            hog = cv2.HOGDescriptor()
            hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
            self.hog = hog

    def detect(self, frame):
        with self._lock:
            self._load()
            return self._detect(frame)

    def _detect(self, frame):
        import cv2    # lazy: no OpenCV in a node that needs none
        if self.kind == 'haar':
            boxes, _, weights = self.classifier.detectMultiScale3(
                to_gray(frame), scaleFactor=self.scale_factor, minNeighbors=self.min_neighbors,
                minSize=(self.min_size, self.min_size), outputRejectLevels=True)
            return [Box(int(x), int(y), int(w), int(h), self.label, float(s))
                    for (x, y, w, h), s in zip(boxes, np.ravel(weights))]
        image = frame if frame.ndim == 3 else cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
        boxes, weights = self.hog.detectMultiScale(image, winStride=(8, 8), padding=(8, 8),
                                                   scale=1.05)
        return [Box(int(x), int(y), int(w), int(h), self.label, float(s))
                for (x, y, w, h), s in zip(boxes, np.ravel(weights))]


def annotate(frame, boxes):
    """A BGR copy of ``frame`` with the boxes drawn and labelled."""
    import cv2    # lazy: no OpenCV in a node that needs none
    image = frame.copy() if frame.ndim == 3 else cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    for b in boxes:
        cv2.rectangle(image, (b.x, b.y), (b.x + b.width, b.y + b.height), (0, 255, 0), 2)
        cv2.putText(image, '%s %.1f' % (b.label, b.score), (b.x, max(12, b.y - 4)),
                    cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 255, 0), 1)
    return image


def iou(a, b):
    """Intersection over union of two boxes (x, y, width, height ...)."""
    x1, y1 = max(a[0], b[0]), max(a[1], b[1])
    x2, y2 = min(a[0] + a[2], b[0] + b[2]), min(a[1] + a[3], b[1] + b[3])
    inter = max(0, x2 - x1) * max(0, y2 - y1)
    union = a[2] * a[3] + b[2] * b[3] - inter
    return inter / float(union) if union else 0.0


def search_frame(detector, raw, compressed=('', b''), max_pixels=MAX_PIXELS):
    """The work of one image task: decode the frame (see
    :func:`~server_select.vision.image_codec.task_frame`), detect, annotate.

    Returns ``(boxes, annotated BGR array)``; a frame that is too large or cannot be
    decoded raises :class:`~server_select.vision.image_codec.ImageError`.
    """
    frame = task_frame(raw, compressed, max_pixels)
    boxes = detector.detect(frame)
    return boxes, annotate(frame, boxes)
