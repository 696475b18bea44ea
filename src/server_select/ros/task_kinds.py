"""What a robot's task streams send: sort tasks and camera frames, as ROS messages.

Each kind gives :class:`~server_select.core.task_flow.TaskFlow` its ``make``, ``check``
and ``run_local``, and the adapter its topics and message types. A request names no server:
the adapter stamps ``server_id`` on each attempt (a task may be sent again elsewhere).
"""

import time

import numpy as np
from rospy.numpy_msg import numpy_msg
from sensor_msgs.msg import Image

from server_select.core import names
from server_select.core.sort_task import check_sorted, fingerprint, make_values, sort_values
from server_select.msg import ImageResult, ImageTask, SortResult, SortTask
from server_select.vision import image_codec
from server_select.vision.detection import search_frame


class SortKind(object):
    """``size`` random int32 values per task, checked on return (length, sum, order)."""

    kind = 'sort'
    task_topic, task_type = names.SORT_TASK_TOPIC, numpy_msg(SortTask)
    result_topic, result_type = names.SORT_RESULT_TOPIC, numpy_msg(SortResult)

    def __init__(self, robot_id, size, seed):
        self.robot_id = robot_id
        self.size = size
        self.rng = np.random.default_rng(seed)

    def make(self, task_id, stamp):
        values = make_values(self.rng, self.size)
        task = SortTask(robot_id=self.robot_id, task_id=task_id, data=values)
        task.header.stamp = stamp
        return task, fingerprint(values)

    def check(self, result, context):
        return check_sorted(result.data, context)

    def run_local(self, _task_id, _stamp):
        values = make_values(self.rng, self.size)
        return check_sorted(sort_values(values, len(values)), fingerprint(values))


class ImageKind(object):
    """Camera frames from a source; where each was taken goes to the search (if any)."""

    kind = 'image'
    task_topic, task_type = names.IMAGE_TASK_TOPIC, ImageTask
    result_topic, result_type = names.IMAGE_RESULT_TOPIC, ImageResult

    def __init__(self, robot_id, source, encoding, search=None, detector=None,
                 max_pixels=1 << 24):
        self.robot_id = robot_id
        self.source = source
        self.encoding = encoding
        self.search = search          # a SearchParticipant, or None
        self.detector = detector      # mode local only
        self.max_pixels = max_pixels
        self.t0 = time.monotonic()

    def capture(self, task_id):
        """A frame from the source, as message fields; the search learns where it was."""
        frame, where = self.source.frame(time.monotonic() - self.t0)
        if self.search is not None:
            self.search.remember(task_id, where)
        return image_codec.from_array(frame, self.encoding)

    def make(self, task_id, stamp):
        encoding, height, width, step, data = self.capture(task_id)
        image = Image(height=height, width=width, encoding=encoding, step=step, data=data)
        image.header.stamp = stamp
        image.header.frame_id = 'robot%d_camera' % self.robot_id
        task = ImageTask(robot_id=self.robot_id, task_id=task_id, image=image)
        task.header.stamp = stamp
        return task, None

    def check(self, result, _context):
        if result.image.width == 0:
            return 'result carries no annotated image'
        return None

    def run_local(self, task_id, _stamp):
        # The same work a server does for a frame (message fields in, detection,
        # annotation), so that robot CPU with and without offloading compare fairly.
        boxes, _ = search_frame(self.detector, *self.capture(task_id),
                                max_pixels=self.max_pixels)
        if self.search is not None:
            self.search.found_in(task_id, [(b.x, b.y, b.width, b.height, b.label)
                                           for b in boxes])
        return None
