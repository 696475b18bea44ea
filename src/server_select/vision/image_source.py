"""Where a robot's camera frames come from (no rospy): a video file, a folder of images,
or a robot moving over a synthetic search area."""

import os

from server_select.vision.search import PathFollower, SearchWorld, lawnmower, sample_image

IMAGE_SUFFIXES = ('.png', '.jpg', '.jpeg', '.bmp', '.ppm', '.pgm', '.tif', '.tiff')


def frame():
    """The benchmarks' camera frame: a photograph with one face, 640x480."""
    import cv2      # (OpenCV only where frames are made: a node loads it when it needs it)
    return cv2.resize(sample_image('astronaut.png'), (640, 480))


def write_frame(folder):
    """The benchmarks' camera frame as an image source in ``folder`` (made if missing)."""
    import cv2
    os.makedirs(folder, exist_ok=True)
    cv2.imwrite(os.path.join(folder, 'face.png'), frame())


class SourceError(ValueError):
    """A frame source that cannot be opened."""


class FolderSource(object):
    """The images of a folder in name order, looping."""

    def __init__(self, path):
        names = sorted(n for n in os.listdir(path) if n.lower().endswith(IMAGE_SUFFIXES))
        if not names:
            raise SourceError('no images (%s) in %s' % (', '.join(IMAGE_SUFFIXES), path))
        self.paths = [os.path.join(path, n) for n in names]
        self.index = 0

    def frame(self, _t):
        import cv2    # lazy: no OpenCV in a node that needs none
        for _ in range(len(self.paths)):
            path = self.paths[self.index % len(self.paths)]
            self.index += 1
            image = cv2.imread(path, cv2.IMREAD_COLOR)
            if image is not None:
                return image, None
        raise SourceError('none of the images in the folder can be read')


class VideoSource(object):
    """The frames of a video file, looping."""

    def __init__(self, path):
        import cv2    # lazy: no OpenCV in a node that needs none
        self.path = path
        self.capture = cv2.VideoCapture(path)
        if not self.capture.isOpened():
            raise SourceError('cannot open video %s' % path)

    def frame(self, _t):
        import cv2    # lazy: no OpenCV in a node that needs none
        ok, image = self.capture.read()
        if not ok:
            self.capture.release()
            self.capture = cv2.VideoCapture(self.path)
            ok, image = self.capture.read()
            if not ok:
                raise SourceError('video %s has no frames' % self.path)
        return image, None


class SearchSource(object):
    """A robot sweeping its strip of a synthetic search area (lawnmower path).

    ``frame(t)`` returns the view and the (x, y) it was taken at.
    """

    def __init__(self, world, strip, strips, speed, spacing=None):
        if not 0 <= strip < strips:
            raise SourceError('strip %d of %d' % (strip, strips))
        self.world = world
        half_w, half_h = world.frame_width / 2.0, world.frame_height / 2.0
        width = (world.width - 2 * half_w) / strips
        x_min = half_w + strip * width
        self.path = PathFollower(
            lawnmower(x_min, x_min + width, half_h, world.height - half_h,
                      spacing or world.frame_height * 0.75), speed)

    def frame(self, t):
        x, y = self.path.position(t)
        return self.world.view(x, y), (x, y)


def open_source(spec, robot_index=0, robots=1, speed=200.0):
    """A source from ``~image_source``: a folder, a video file, or ``search:<world.yaml>``."""
    if spec.startswith('search:'):
        return SearchSource(SearchWorld.load(spec[len('search:'):]), robot_index, robots, speed)
    if os.path.isdir(spec):
        return FolderSource(spec)
    if os.path.isfile(spec):
        return VideoSource(spec)
    raise SourceError('image source %r is neither a folder, a video file nor search:<world>'
                      % spec)
