"""ORB features of camera frames, as a plug-in task type (``server_select.tasks.orb:Orb``).

Robot settings (``~orb/...``): ``source`` (a folder, a video file or ``search:<area.yaml>``,
required), ``rate`` (Hz, 1), ``max_features`` (500), ``quality`` (JPEG, 80).
"""

import time

from sensor_msgs.msg import CompressedImage
from std_msgs.msg import Header

from server_select.msg import OrbResult, OrbTask
from server_select.ros.plugins import TaskPlugin
from server_select.vision import image_codec
from server_select.vision.features import orb_features
from server_select.vision.image_source import open_source


class Orb(TaskPlugin):
    """Keypoints and binary descriptors of a frame, found by the server."""

    kind = 'orb'
    newest_wins = True        # camera frames: only the newest is worth anything
    task_type, result_type = OrbTask, OrbResult
    task_topic, result_topic = 'task_orb', 'processed_orb'

    def __init__(self, robot_id, settings):
        super(Orb, self).__init__(robot_id, settings)
        self.max_features = int(settings.get('max_features', 500))
        self.quality = int(settings.get('quality', 80))
        self.source = None
        if robot_id is not None:
            if 'source' not in settings:
                raise ValueError('source: required (a folder, a video file or search:AREA)')
            self.source = open_source(settings['source'])
            self.t0 = time.monotonic()

    def _frame(self):
        return self.source.frame(time.monotonic() - self.t0)[0]

    def make(self, task_id, stamp):
        fmt, data = image_codec.encode(self._frame(), self.quality)
        return OrbTask(header=Header(stamp=stamp), robot_id=self.robot_id, task_id=task_id,
                       frame=CompressedImage(format=fmt, data=data),
                       max_features=self.max_features), None

    def check(self, result, _context):
        if result.count > self.max_features or len(result.points) != 2 * result.count or \
                len(result.descriptors) != 32 * result.count:
            return 'inconsistent result: %d keypoints, %d coordinates, %d descriptor bytes' % (
                result.count, len(result.points), len(result.descriptors))
        return None

    def run_local(self, _task_id, _stamp):
        orb_features(self._frame(), self.max_features)
        return None

    def handle(self, task, result):
        frame = image_codec.decode(task.frame.format, task.frame.data)
        points, descriptors = orb_features(frame, task.max_features)
        result.count = len(points)
        result.points = points.ravel().tolist()
        result.descriptors = descriptors.tobytes()

    rehearse = handle     # (it acts on its result alone)
