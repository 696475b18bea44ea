"""Cooperative search (no rospy): a synthetic area with real photographs hidden in it,
robot paths over it, and the registry of targets found so far."""

import collections
import importlib.util
import math
import os
import threading

import yaml

from server_select.core.util.lazy import deferred

np = deferred('numpy')

Target = collections.namedtuple('Target', 'name x y width height')
Found = collections.namedtuple('Found', 'robot_id task_id label x y stamp')


class SearchError(ValueError):
    """A search world that cannot be built."""


def sample_image(name):
    """A photograph shipped in scikit-image's wheel (``skimage/data/<name>``), BGR.

    Located without importing scikit-image; nothing is downloaded.
    """
    import cv2    # lazy: no OpenCV in a node that needs none
    spec = importlib.util.find_spec('skimage')
    if spec is None or not spec.submodule_search_locations:
        raise SearchError('scikit-image is not installed: its wheel ships the sample photos')
    path = os.path.join(list(spec.submodule_search_locations)[0], 'data', name)
    image = cv2.imread(path, cv2.IMREAD_COLOR)
    if image is None:
        raise SearchError('cannot read sample image %s' % path)
    return image


class SearchWorld(object):
    """A textured area of ``width`` x ``height`` pixels with target photos placed in it.

    ``view(x, y)`` is what a robot's downward camera sees centred on (x, y): a
    ``frame_width`` x ``frame_height`` crop (outside the area is dark).
    """

    def __init__(self, width, height, targets, seed=0, frame_width=640, frame_height=480):
        import cv2    # lazy: no OpenCV in a node that needs none
        self.width, self.height = int(width), int(height)
        self.frame_width, self.frame_height = int(frame_width), int(frame_height)
        rng = np.random.default_rng(seed)
        # ground: smooth random texture, no faces in it
        small = rng.integers(60, 140, size=(self.height // 40 + 2, self.width // 40 + 2, 3),
                             dtype=np.uint8)
        ground = cv2.resize(small, (self.width, self.height), interpolation=cv2.INTER_CUBIC)
        noise = rng.integers(-12, 12, size=ground.shape, dtype=np.int16)
        self.image = np.clip(ground.astype(np.int16) + noise, 0, 255).astype(np.uint8)
        self.targets = []
        for spec in targets:
            photo = sample_image(spec.get('image', 'astronaut.png'))
            size = int(spec.get('size', 200))
            photo = cv2.resize(photo, (size, size * photo.shape[0] // photo.shape[1]))
            if spec.get('mirror'):
                photo = photo[:, ::-1]
            h, w = photo.shape[:2]
            x0, y0 = int(spec['x']) - w // 2, int(spec['y']) - h // 2
            if x0 < 0 or y0 < 0 or x0 + w > self.width or y0 + h > self.height:
                raise SearchError('target %s does not fit in the area' % spec.get('name'))
            self.image[y0:y0 + h, x0:x0 + w] = photo
            self.targets.append(Target(str(spec.get('name', 'target%d' % len(self.targets))),
                                       float(spec['x']), float(spec['y']), w, h))

    @classmethod
    def load(cls, path):
        try:
            with open(path) as stream:
                data = yaml.safe_load(stream)
            return cls(data['width'], data['height'], data.get('targets', []),
                       seed=data.get('seed', 0), frame_width=data.get('frame_width', 640),
                       frame_height=data.get('frame_height', 480))
        except (OSError, KeyError, TypeError, yaml.YAMLError) as error:
            raise SearchError('%s: %s' % (path, error))

    def view_origin(self, x, y):
        return int(round(x)) - self.frame_width // 2, int(round(y)) - self.frame_height // 2

    def view(self, x, y):
        frame = np.zeros((self.frame_height, self.frame_width, 3), dtype=np.uint8)
        x0, y0 = self.view_origin(x, y)
        sx0, sy0 = max(0, x0), max(0, y0)
        sx1 = min(self.width, x0 + self.frame_width)
        sy1 = min(self.height, y0 + self.frame_height)
        if sx1 > sx0 and sy1 > sy0:
            frame[sy0 - y0:sy1 - y0, sx0 - x0:sx1 - x0] = self.image[sy0:sy1, sx0:sx1]
        return frame

    def to_world(self, view_x, view_y, box):
        """Area coordinates of the centre of ``box`` (x, y, w, h) seen from (view_x, view_y)."""
        x0, y0 = self.view_origin(view_x, view_y)
        return x0 + box[0] + box[2] / 2.0, y0 + box[1] + box[3] / 2.0

    def target_at(self, x, y, radius):
        """The name of the placed target nearest (x, y) within ``radius``, or None."""
        best = None
        for t in self.targets:
            d = math.hypot(t.x - x, t.y - y)
            if d <= radius and (best is None or d < best[0]):
                best = (d, t.name)
        return best[1] if best else None


def lawnmower(x_min, x_max, y_min, y_max, spacing):
    """Waypoints sweeping the rectangle in rows ``spacing`` apart."""
    points, y, left = [], y_min, True
    while y <= y_max + 1e-9:
        row = [(x_min, y), (x_max, y)]
        points.extend(row if left else row[::-1])
        left = not left
        y += spacing
    return points


class PathFollower(object):
    """Position along a waypoint path at a constant ``speed`` (units/s), then looping."""

    def __init__(self, waypoints, speed):
        if len(waypoints) < 1 or speed <= 0:
            raise SearchError('a path needs waypoints and a positive speed')
        self.points = [tuple(map(float, p)) for p in waypoints]
        self.speed = float(speed)
        legs = list(zip(self.points, self.points[1:] + self.points[:1]))
        self.legs = [(a, b, math.hypot(b[0] - a[0], b[1] - a[1])) for a, b in legs]
        self.length = sum(l for _, _, l in self.legs)

    def position(self, t):
        if self.length == 0:
            return self.points[0]
        s = (t * self.speed) % self.length
        for a, b, l in self.legs:
            if s <= l and l > 0:
                f = s / l
                return a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f
            s -= l
        return self.points[0]


class TargetRegistry(object):
    """The targets known to be found, merged by distance: who, where, when; at most
    ``limit`` of them, so that no sender can grow it without a bound.

    Thread-safe: the robot's detection callback and its found_targets subscriber both add.
    """

    def __init__(self, radius, limit=1000):
        self.radius = float(radius)
        self.limit = int(limit)
        self._lock = threading.Lock()
        self._found = []

    def add(self, found):
        """Record ``found`` unless a target within ``radius`` is known or the registry
        holds ``limit`` targets; True if recorded."""
        with self._lock:
            if len(self._found) >= self.limit:
                return False
            for f in self._found:
                if math.hypot(f.x - found.x, f.y - found.y) <= self.radius:
                    return False
            self._found.append(found)
            return True

    def full(self):
        with self._lock:
            return len(self._found) >= self.limit

    def all(self):
        with self._lock:
            return list(self._found)
