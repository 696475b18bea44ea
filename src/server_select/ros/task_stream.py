"""ROS wiring of one task stream of a robot (the logic is in core.task_flow).

Like tf2_ros's ``TransformListener``, :class:`TaskStream` only owns the publishers,
subscribers and timers, and forwards into its :class:`TaskFlow`.
"""

import math
import time

import rospy

from server_select.core import names
from server_select.core.stats import format_ms, summarize
from server_select.core.task_flow import TaskFlow
from server_select.msg import TaskReport


class TaskStream(object):
    """Sends tasks of one ``kind`` (see :mod:`server_select.ros.task_kinds`) at ``rate``.

    The stream waits until ``ready()`` and, unless the robot works ``local``ly, until its
    task and result topics are connected; then it sends a task every ``1/rate`` s (at most
    ``limit``, 0: no limit) and publishes one ``task_report`` per task.
    """

    def __init__(self, robot_id, kind, rate, limit, timeout, target, ready, ids, local=False):
        self.robot_id = robot_id
        self.kind = kind
        self.rate = rate
        self.limit = limit
        self.ready = ready
        self.local = local
        self.started = False
        self.flow = TaskFlow(kind.kind, timeout, target, kind.make, self._publish_task,
                             kind.check, self._report, kind.run_local, ids, clock=time.monotonic)
        self.task_pub = self.result_sub = self.report_pub = None
        self.timers = []

    def start(self):
        self.report_pub = rospy.Publisher(names.TASK_REPORT_TOPIC, TaskReport, queue_size=100)
        if not self.local:
            self.task_pub = rospy.Publisher(self.kind.task_topic, self.kind.task_type,
                                            queue_size=100)
            self.result_sub = rospy.Subscriber(
                self.kind.result_topic, self.kind.result_type, self.on_result, queue_size=100,
                tcp_nodelay=True, buff_size=1 << 24)
        self.timers = [rospy.Timer(rospy.Duration(1.0 / self.rate), self.on_timer),
                       rospy.Timer(rospy.Duration(0.05), lambda _e: self.flow.expire())]

    def wired(self):
        return self.local or (self.task_pub.get_num_connections() > 0
                              and self.result_sub.get_num_connections() > 0)

    def on_timer(self, _event):
        if rospy.is_shutdown() or (self.limit and self.flow.sent >= self.limit):
            return
        if not self.started:
            if not (self.ready() and self.wired()):
                rospy.loginfo_throttle(5.0, 'robot %d: %s tasks wait for a server'
                                       % (self.robot_id, self.flow.kind))
                return
            self.started = True
            rospy.loginfo('robot %d: sending %s tasks', self.robot_id, self.flow.kind)
        self.flow.send_next(rospy.Time.now())

    def _publish_task(self, request):
        self.task_pub.publish(request)

    def on_result(self, result):
        if result.robot_id != self.robot_id:
            return
        outcome = self.flow.resolve(result.task_id, result.server_id, result.ok, result.error,
                                    result)
        if isinstance(outcome, str):
            rospy.logwarn_throttle(
                5.0, 'robot %d: ignored %s %s result for task %d from server %d'
                % (self.robot_id, outcome, self.flow.kind, result.task_id, result.server_id))
        elif outcome.answered_by != outcome.server_id:
            rospy.logwarn('robot %d: task %d sent to server %d was answered by server %d',
                          self.robot_id, result.task_id, outcome.server_id, outcome.answered_by)

    def _report(self, outcome):
        msg = TaskReport(robot_id=self.robot_id, task_id=outcome.task_id, kind=outcome.kind,
                         server_id=outcome.server_id, answered_by=outcome.answered_by,
                         ok=outcome.ok, error=outcome.error,
                         rtt=outcome.rtt if outcome.rtt is not None else math.nan)
        msg.header.stamp = outcome.stamp
        if not outcome.ok:
            rospy.logerr('robot %d: %s task %d (server %d) failed: %s', self.robot_id,
                         outcome.kind, outcome.task_id, outcome.server_id, outcome.error)
        self.report_pub.publish(msg)

    def summary(self):
        flow = self.flow
        return '%s: %d sent, %d ok, %d failed, %d pending, round trip %s' % (
            flow.kind, flow.sent, flow.ok, flow.failed, len(flow),
            format_ms(summarize(list(flow.rtts)), ('median', 'p99', 'max')))

    def shutdown(self):
        for timer in self.timers:
            timer.shutdown()
