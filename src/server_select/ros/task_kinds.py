"""What a robot's task streams send: sort tasks and camera frames, as ROS messages.

Each kind gives :class:`~server_select.core.task_flow.TaskFlow` its ``make``, ``check``
and ``run_local``, and the adapter its topics and message types. A request names no server:
the adapter stamps ``server_id`` on each attempt (a task may be sent again elsewhere).
"""

import time

import numpy as np
from rospy.numpy_msg import numpy_msg
from sensor_msgs.msg import CompressedImage, Image
from std_msgs.msg import Header

from server_select.core import names
from server_select.core.params import ParamError
from server_select.core.sort_task import check_sorted, fingerprint, make_values, sort_values
from server_select.msg import ImageResult, ImageTask, SortResult, SortTask
from server_select.ros.camera import TopicSource
from server_select.ros.plugins import load as load_plugin
from server_select.ros.search import SearchParticipant
from server_select.vision import image_codec
from server_select.vision.detection import DetectorError, make_detector, search_frame
from server_select.vision.image_source import SourceError, open_source
from server_select.vision.search import SearchError


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
    newest_wins = True        # a frame nobody waits for any more is worth nothing
    task_topic, task_type = names.IMAGE_TASK_TOPIC, ImageTask
    result_topic, result_type = names.IMAGE_RESULT_TOPIC, ImageResult

    def __init__(self, robot_id, source, encoding, search=None, detector=None,
                 max_pixels=1 << 24, transport='raw', quality=80, start=0.0):
        self.robot_id = robot_id
        self.source = source
        self.encoding = encoding
        self.transport, self.quality = transport, quality
        self.search = search          # a SearchParticipant, or None
        self.detector = detector      # mode local only
        self.max_pixels = max_pixels
        # the source's time zero: now, or the epoch time ``start`` (a shared clock)
        self.t0 = time.monotonic() - (time.time() - start if start else 0.0)

    def ready(self):
        """Whether a frame is there to send (a camera topic may not have sent one yet)."""
        return getattr(self.source, 'ready', lambda: True)()

    def capture(self, task_id):
        """A frame from the source in ``encoding``; the search learns where it was."""
        frame, where = self.source.frame(time.monotonic() - self.t0)
        if self.search is not None:
            self.search.remember(task_id, where)
        return image_codec.convert(frame, self.encoding)

    def make(self, task_id, stamp):
        frame = self.capture(task_id)
        header = Header(stamp=stamp, frame_id='robot%d_camera' % self.robot_id)
        task = ImageTask(header=Header(stamp=stamp), robot_id=self.robot_id, task_id=task_id)
        if self.transport == 'compressed':
            fmt, data = image_codec.encode(frame, self.quality)
            task.compressed = CompressedImage(header=header, format=fmt, data=data)
        else:
            encoding, height, width, step, data = image_codec.from_array(frame, self.encoding)
            task.image = Image(header=header, height=height, width=width, encoding=encoding,
                               step=step, data=data)
        return task, None

    def check(self, result, _context):
        if result.image.width == 0 and not result.compressed.data:
            return 'result carries no annotated image'
        return None

    def run_local(self, task_id, _stamp):
        # The same work a server does for a frame (message fields in, detection,
        # annotation), so that robot CPU with and without offloading compare fairly.
        boxes, _ = search_frame(self.detector,
                                image_codec.from_array(self.capture(task_id), self.encoding),
                                max_pixels=self.max_pixels)
        if self.search is not None:
            self.search.found_in(task_id, [(b.x, b.y, b.width, b.height, b.label)
                                           for b in boxes])
        return None


def image_kind(robot_id, mode, param):
    """The camera stream the parameters describe (``param(name)`` reads one): a topic
    (``~image_topic``) or a source (``~image_source``); ParamError when they are wrong."""
    if param('image_source') and param('image_topic'):
        raise ParamError('~image_source and ~image_topic: set one of them, not both')
    if param('image_topic'):
        source = TopicSource(param('image_topic'), param('max_image_pixels'))
    else:
        try:
            source = open_source(param('image_source'), param('robot_index'),
                                 param('robot_count'), param('speed'))
        except (SourceError, SearchError, OSError) as error:
            raise ParamError('~image_source: %s' % error)
    detector = None
    if mode == 'local':
        try:
            detector = make_detector(param)
        except DetectorError as error:
            raise ParamError('~detector/~cascade: %s' % error)
    search = SearchParticipant(robot_id, param('merge_radius'), getattr(source, 'world', None))
    return ImageKind(robot_id, source, param('image_encoding'), search, detector,
                     param('max_image_pixels'), param('image_transport'), param('jpeg_quality'),
                     param('sweep_start'))


def stream_kinds(robot_id, mode, param):
    """``[(task kind, rate)]`` of each stream the parameters ask for (``param(name)`` reads
    one); ParamError when they ask for none or are wrong."""
    kinds = []
    if param('sort_tasks'):
        kinds.append((SortKind(robot_id, param('task_size'), param('seed', default=robot_id)),
                      param('task_rate')))
    if param('image_source') or param('image_topic'):
        kinds.append((image_kind(robot_id, mode, param), param('frame_rate')))
    kinds += [(plugin, plugin.rate) for plugin in
              (load_plugin(spec, robot_id) for spec in param('task_plugins'))]
    if not kinds:
        raise ParamError('~sort_tasks is false, and neither ~image_source, ~image_topic '
                         'nor ~task_plugins is set: no tasks to send')
    return kinds
