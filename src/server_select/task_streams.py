"""The robot's task streams: sort tasks and image tasks, sent to the selected server or
processed locally, each ending in exactly one task_report."""

import threading
import time

import numpy as np
import rospy
from rospy.numpy_msg import numpy_msg
from sensor_msgs.msg import Image

from server_select import image_codec, names
from server_select.detection import annotate
from server_select.msg import (Detections, FoundTarget, ImageResult, ImageTask, SortResult,
                               SortTask, TaskReport)
from server_select.sort_task import check_sorted, fingerprint, make_values, sort_values
from server_select.search import Found
from server_select.stats import format_ms, summarize
from server_select.tracker import NONE, Outcome, TaskTracker

LOCAL = -2   # answered_by of a task the robot processed itself (mode local)


class TaskStream(object):
    """Common part of a stream: the timer, the tracker, the reports and the summary.

    Subclasses say how a task is made (``make``), checked (``check``) and processed in the
    robot itself (``run_locally``, mode ``local``).
    """

    kind = 'task'

    def __init__(self, robot, rate, limit, timeout, task_topic, task_type, result_topic,
                 result_type, buff_size=1 << 16):
        self.robot = robot
        self.limit = limit
        self.tracker = TaskTracker(timeout)
        self._lock = threading.Lock()
        self.sent = 0
        self.rtts = []
        self.failed = 0
        self.started = False
        self.task_pub = rospy.Publisher(task_topic, task_type, queue_size=100)
        self.result_sub = rospy.Subscriber(result_topic, result_type, self.on_result,
                                           queue_size=100, tcp_nodelay=True, buff_size=buff_size)
        self.timer = rospy.Timer(rospy.Duration(1.0 / rate), self.on_timer)
        self.expire_timer = rospy.Timer(rospy.Duration(0.05), self.on_expire)

    def wired(self):
        return self.task_pub.get_num_connections() > 0 and self.result_sub.get_num_connections() > 0

    def on_timer(self, _event):
        if rospy.is_shutdown() or (self.limit and self.sent >= self.limit):
            return
        if not self.started:
            if not self.robot.ready(self):
                rospy.loginfo_throttle(5.0, 'robot %d: %s tasks wait for a server'
                                       % (self.robot.robot_id, self.kind))
                return
            self.started = True
            rospy.loginfo('robot %d: sending %s tasks', self.robot.robot_id, self.kind)
        self.send()

    def send(self):
        task_id = self.robot.next_task_id()
        self.sent += 1
        stamp = rospy.Time.now()
        if self.robot.mode == 'local':
            self.run_locally(task_id, stamp)
            return
        target = self.robot.target()
        if target == NONE:
            self.report(self.tracker.fail(task_id, time.perf_counter(), NONE,
                                          'no server selected'), stamp)
            return
        msg, context = self.make(task_id, target, stamp)
        if msg is None:
            return
        self.tracker.sent(task_id, time.perf_counter(), target, (context, stamp))
        self.task_pub.publish(msg)

    def on_result(self, result):
        if result.robot_id != self.robot.robot_id:
            return
        now = time.perf_counter()
        pending = self.tracker.context(result.task_id)
        error = result.error
        if pending is not None and result.ok:
            error = self.check(result, pending[0]) or ''
        outcome = self.tracker.resolve(result.task_id, now, result.server_id,
                                       result.ok and not error, error)
        if outcome is None:
            rospy.logwarn('robot %d: %s result for task %d from server %d is a duplicate or '
                          'arrived after its timeout', self.robot.robot_id, self.kind,
                          result.task_id, result.server_id)
            return
        if outcome.answered_by != outcome.server_id:
            rospy.logwarn('robot %d: task %d sent to server %d was answered by server %d',
                          self.robot.robot_id, result.task_id, outcome.server_id,
                          outcome.answered_by)
        self.report(outcome, pending[1])
        if outcome.ok:
            self.on_success(result, pending[0])

    def on_success(self, result, context):
        pass

    def on_expire(self, _event):
        for outcome in self.tracker.expire(time.perf_counter()):
            self.report(outcome, None)

    def report(self, outcome, stamp):
        msg = TaskReport(robot_id=self.robot.robot_id, task_id=outcome.task_id, kind=self.kind,
                         server_id=outcome.server_id, answered_by=outcome.answered_by,
                         ok=outcome.ok, error=outcome.error, rtt=outcome.rtt)
        if stamp is not None:
            msg.header.stamp = stamp
        with self._lock:
            if outcome.ok:
                self.rtts.append(outcome.rtt)
            else:
                self.failed += 1
        if not outcome.ok:
            rospy.logerr('robot %d: %s task %d (server %d) failed: %s', self.robot.robot_id,
                         self.kind, outcome.task_id, outcome.server_id, outcome.error)
        self.robot.report_pub.publish(msg)

    def report_local(self, task_id, stamp, start):
        """Report a task the robot processed itself (mode ``local``)."""
        self.report(Outcome(task_id, start, LOCAL, LOCAL, True, '', time.perf_counter() - start),
                    stamp)

    def summary(self):
        with self._lock:
            rtts, failed = list(self.rtts), self.failed
        return '%s: %d sent, %d ok, %d failed, %d pending, round trip %s' % (
            self.kind, self.sent, len(rtts), failed, len(self.tracker),
            format_ms(summarize(rtts), ('median', 'p99', 'max')))

    def shutdown(self):
        self.timer.shutdown()
        self.expire_timer.shutdown()


class SortStream(TaskStream):
    """``~task_size`` random int32 values per task, checked on return."""

    kind = 'sort'

    def __init__(self, robot, rate, limit, timeout, size, seed):
        self.size = size
        self.rng = np.random.default_rng(seed)
        super(SortStream, self).__init__(robot, rate, limit, timeout, names.SORT_TASK_TOPIC,
                                         numpy_msg(SortTask), names.SORT_RESULT_TOPIC,
                                         numpy_msg(SortResult), buff_size=1 << 24)

    def make(self, task_id, target, stamp):
        values = make_values(self.rng, self.size)
        task = SortTask(robot_id=self.robot.robot_id, task_id=task_id, server_id=target,
                        data=values)
        task.header.stamp = stamp
        return task, fingerprint(values)

    def check(self, result, context):
        return check_sorted(result.data, context)

    def run_locally(self, task_id, stamp):
        start = time.perf_counter()
        values = make_values(self.rng, self.size)
        check_sorted(sort_values(values, len(values)), fingerprint(values))
        self.report_local(task_id, stamp, start)


class ImageStream(TaskStream):
    """Camera frames from a source; detections feed the shared record of found targets."""

    kind = 'image'

    def __init__(self, robot, rate, limit, timeout, source, encoding, registry, found_pub,
                 local_detector=None):
        self.source = source
        self.encoding = encoding
        self.registry = registry
        self.found_pub = found_pub
        self.local_detector = local_detector   # mode local only
        self.t0 = time.monotonic()
        self.detections_sub = None
        self._views = {}   # task id -> where the frame was taken; before the timer starts
        super(ImageStream, self).__init__(robot, rate, limit, timeout, names.IMAGE_TASK_TOPIC,
                                          ImageTask, names.IMAGE_RESULT_TOPIC, ImageResult,
                                          buff_size=1 << 24)
        self.detections_sub = rospy.Subscriber(names.DETECTIONS_TOPIC, Detections,
                                               self.on_detections, queue_size=100,
                                               tcp_nodelay=True)

    def capture(self):
        frame, where = self.source.frame(time.monotonic() - self.t0)
        return frame, where

    def make(self, task_id, target, stamp):
        frame, where = self.capture()
        encoding, height, width, step, data = image_codec.from_array(frame, self.encoding)
        image = Image(height=height, width=width, encoding=encoding, step=step, data=data)
        image.header.stamp = stamp
        image.header.frame_id = 'robot%d_camera' % self.robot.robot_id
        task = ImageTask(robot_id=self.robot.robot_id, task_id=task_id, server_id=target,
                         image=image)
        task.header.stamp = stamp
        with self._lock:
            self._views[task_id] = where
            while len(self._views) > 1000:
                self._views.pop(next(iter(self._views)))
        return task, where

    def check(self, result, context):
        if result.image.width == 0:
            return 'result carries no annotated image'
        return None

    def on_detections(self, msg):
        """Targets found in this robot's frames become shared records, once."""
        if msg.robot_id != self.robot.robot_id or not msg.detections:
            return
        with self._lock:
            where = self._views.get(msg.task_id)
        self.record([(d.roi.x_offset, d.roi.y_offset, d.roi.width, d.roi.height, d.label)
                     for d in msg.detections], where, msg.task_id)

    def record(self, boxes, where, task_id):
        world = getattr(self.source, 'world', None)
        for x, y, w, h, label in boxes:
            if world is not None and where is not None:
                wx, wy = world.to_world(where[0], where[1], (x, y, w, h))
            else:
                wx, wy = x + w / 2.0, y + h / 2.0   # no map: frame coordinates
            found = Found(self.robot.robot_id, task_id, label, wx, wy, rospy.get_time())
            if self.registry.add(found):
                msg = FoundTarget(robot_id=found.robot_id, task_id=task_id, label=label,
                                  x=wx, y=wy)
                msg.header.stamp = rospy.Time.from_sec(found.stamp)
                rospy.loginfo('robot %d: found %s at (%.0f, %.0f)', self.robot.robot_id,
                              label, wx, wy)
                self.found_pub.publish(msg)

    def run_locally(self, task_id, stamp):
        # The same work a server does for a frame (message conversion, detection,
        # annotation), so that robot CPU with and without offloading compare fairly.
        start = time.perf_counter()
        frame, where = self.capture()
        encoding, height, width, step, data = image_codec.from_array(frame, self.encoding)
        frame = image_codec.to_array(encoding, height, width, step, data)
        boxes = self.local_detector.detect(frame)
        annotate(frame, boxes)
        self.report_local(task_id, stamp, start)
        self.record([(b.x, b.y, b.width, b.height, b.label) for b in boxes], where, task_id)
