"""ROS wiring of one task stream of a robot (the logic is in core.task_flow).

Like tf2_ros's ``TransformListener``, :class:`TaskStream` only owns the publishers,
subscribers and timers, and forwards into its :class:`TaskFlow`.
"""

import math
import time

import rospy

from server_select.core.config import names
from server_select.core.util.pacer import Pacer
from server_select.core.util.stats import format_ms, summarize
from server_select.core.flow.outcome import STOPPED, cut_off
from server_select.core.flow.task_flow import ENDED, OUTRUN, RETRIED, TaskFlow
from server_select.msg import TaskReport
from server_select.ros.graph import publisher_of, unheard
from server_select.ros.senders import SenderGate
from server_select.ros.node import fleet, flush
from server_select.ros.routing import BroadcastRoute
from server_select.ros.seal import SealedPublisher


class TaskStream(object):
    """Sends tasks of one ``kind`` (a :class:`~server_select.ros.plugins.TaskPlugin`) at
    ``rate``.

    The stream waits until ``ready()`` and, unless the robot works ``local``ly, until its
    task and result topics are connected, and until every node of ``listeners`` (a
    recorder that must see every task) hears its task reports, and its tasks where it
    subscribes to them; then it sends a task every ``1/rate`` s (at most ``limit``, 0: no
    limit) and publishes one ``task_report`` per task. A result counts only if the node
    ``expected_publisher(server, refresh)`` names published it (a
    :class:`~server_select.ros.senders.SenderGate`).
    With ``load`` (a :class:`~server_select.core.load.robot_load.RobotLoad`: load-aware),
    each attempt
    tells its server the seconds its robot still waits (``budget``), and the load board
    hears where tasks went. A send that ``max_in_flight`` held back goes as soon as a task
    ends.

    One thread paces the stream (a :class:`~server_select.core.util.pacer.Pacer`): it
    wakes when a task is due (every ``1/rate`` s of the wall clock, as the tasks'
    deadlines), when an attempt's deadline, a hedge or a task's timeout comes, and when a
    result changes what is due; between those it sleeps (a timer polling at 50 Hz cost a
    robot about 1 % of this host's core by itself).
    """

    def __init__(self, robot_id, kind, rate, limit, ready, flow_args, local=False,
                 expected_publisher=None, route=BroadcastRoute, load=None, listeners=()):
        self.robot_id, self.kind, self.rate, self.limit = robot_id, kind, rate, limit
        self.listeners = list(listeners)
        self.ready, self.local, self.load = ready, local, load
        self.senders = SenderGate('robot %d' % robot_id, 'server {key}',
                                  lookup=expected_publisher)
        self.started = False
        self._no_input_since = None
        self.flow = TaskFlow(kind.kind, make=kind.make, publish=self._publish_task,
                             check=kind.check, report=self._report, run_local=kind.run_local,
                             clock=time.monotonic, **flow_args)
        self.route = None if local else route(robot_id, kind, self.on_result)
        self.node_of = expected_publisher
        self.report_pub = None
        self.period = 1.0 / rate
        self._next_send = None
        self.pacer = Pacer(self._act, self._next_time, name='%s tasks' % kind.kind,
                           on_error=self._on_error)

    def start(self):
        self.report_pub = SealedPublisher(fleet(names.TASK_REPORT_TOPIC), TaskReport,
                                          queue_size=100)
        if self.route is not None:
            self.route.start()
        self._next_send = time.monotonic() + self.period
        self.pacer.start()

    def _next_time(self):
        if self.flow.due():
            return 0.0
        wake = self.flow.next_wake()
        return self._next_send if wake is None else min(wake, self._next_send)

    def _act(self):
        if rospy.is_shutdown():
            self.pacer.stop()
            return
        now = time.monotonic()
        if now >= self._next_send:      # steady: one period on; fallen behind: from now
            self._next_send += self.period
            if self._next_send <= now:
                self._next_send = now + self.period
            self.on_timer()
        self.flow.tick()
        if self.flow.due() and not rospy.is_shutdown():
            self.flow.send_next(rospy.Time.now())

    def _on_error(self, error):
        rospy.logerr_throttle(5.0, 'robot %d: %s tasks: %s: %s' % (
            self.robot_id, self.flow.kind, type(error).__name__, error))

    def wired(self):
        """Whether the first candidate's task topic and our result topic are connected."""
        candidates = self.flow.candidates()
        return bool(candidates) and self.wired_to(candidates[0])

    def deaf(self):
        """The nodes of ``listeners`` that do not hear our task reports yet, or our tasks
        where they subscribe to them."""
        return unheard(self.listeners, self.report_pub, self.route.publishers()
                       if self.route is not None else [], rospy.get_name()) \
            if self.listeners else []

    def wired_to(self, server):
        """Whether our task topic reaches ``server`` (and our result topic hears one)."""
        return self.route is None or self.route.wired(
            server, self.node_of(server) if self.node_of else None)

    def on_timer(self):
        if rospy.is_shutdown() or (self.limit and self.flow.sent >= self.limit):
            return
        if not self.kind.ready():
            # a camera slower than the task rate leaves some ticks without a frame: only
            # a wait of two periods (at least 1 s) is worth a line
            now = time.monotonic()
            self._no_input_since = self._no_input_since or now
            if now - self._no_input_since > max(1.0, 2.0 / self.rate):
                rospy.loginfo_throttle(5.0, 'robot %d: no input for %s tasks from %s for '
                                       '%.1f s' % (self.robot_id, self.flow.kind,
                                                   self.kind.input,
                                                   now - self._no_input_since))
            return
        self._no_input_since = None
        if not self.started:
            deaf = self.deaf()
            if deaf or not (self.ready() and self.wired()):
                rospy.loginfo_throttle(5.0, 'robot %d: %s tasks wait for %s' % (
                    self.robot_id, self.flow.kind, '%s to hear them' % ', '.join(deaf)
                    if deaf else 'a server'))
                return
            self.started = True
            rospy.loginfo('robot %d: sending %s tasks', self.robot_id, self.flow.kind)
        self.flow.send_next(rospy.Time.now())

    def _publish_task(self, request, server, budget):
        request.server_id = server
        if self.load is not None:
            if hasattr(request, 'budget'):
                request.budget = budget
            self.load.sent(server, self.flow.kind)
        self.route.publish(request, server)

    def on_result(self, result):
        if result.robot_id != self.robot_id:
            return
        if not self.senders.admits(result, lambda: 'a %s result for task %d claiming server '
                                   '%d' % (self.flow.kind, result.task_id, result.server_id),
                                   result.server_id):
            return
        busy = bool(getattr(result, 'busy', False))
        status = self.flow.resolve(result.task_id, result.server_id, result.ok, result.error,
                                   result, busy=busy).status
        if status == RETRIED or self.flow.due():     # a new deadline, or a held send may go
            self.pacer.poke()
        if status == RETRIED and busy:
            rospy.logwarn_throttle(5.0, 'robot %d: server %d refused %s task %d as busy (%s): '
                                   'sent to the next server (%d busy answers so far)'
                                   % (self.robot_id, result.server_id, self.flow.kind,
                                      result.task_id, result.error, self.flow.busy))
        elif status == RETRIED:
            rospy.logwarn('robot %d: %s task %d failed on server %d (%s): sent to the next '
                          'server', self.robot_id, self.flow.kind, result.task_id,
                          result.server_id, result.error)
        elif status == OUTRUN:      # a hedge's losing copy: expected, and counted
            rospy.logdebug('robot %d: %s task %d answered by server %d after another copy',
                           self.robot_id, self.flow.kind, result.task_id, result.server_id)
        elif status != ENDED and not rospy.is_shutdown():     # (stopping: tasks cut off)
            rospy.logwarn_throttle(
                5.0, 'robot %d: ignored %s %s result for task %d from server %d (%s)'
                % (self.robot_id, status, self.flow.kind, result.task_id, result.server_id,
                   publisher_of(result)))

    def _report(self, outcome):
        msg = TaskReport(robot_id=self.robot_id, task_id=outcome.task_id, kind=outcome.kind,
                         server_id=outcome.server_id, answered_by=outcome.answered_by,
                         ok=outcome.ok, error=outcome.error, attempts=outcome.attempts,
                         rtt=outcome.rtt if outcome.rtt is not None else math.nan)
        msg.header.stamp = outcome.stamp
        if not outcome.ok and not cut_off(outcome.error):   # (a stop's cut is no fault)
            rospy.logerr_throttle(1.0, 'robot %d: %s task %d (server %d) failed: %s (%d failed '
                                  'so far)' % (self.robot_id, outcome.kind, outcome.task_id,
                                               outcome.server_id, outcome.error,
                                               self.flow.failed))
        self.report_pub.publish(msg)

    def summary(self):
        flow = self.flow
        outrun = flow.ignored[OUTRUN]
        ignored = sum(flow.ignored.values()) - outrun
        overload = ', '.join('%d %s' % (n, what) for n, what in (
            (flow.busy, 'busy answers'), (flow.skipped, 'skipped for a newer task'),
            (flow.superseded, 'dropped for a newer task'),
            (flow.unfunded, 'extra sends over the retry budget')) if n)
        return '%s: %d sent, %d ok, %d failed, %d pending, %d re-sent%s%s%s%s, round trip %s' % (
            flow.kind, flow.sent, flow.ok, flow.failed, len(flow), flow.resent,
            ', %d hedged' % flow.hedged if flow.hedge is not None else '',
            ', %d copies answered after the first' % outrun if outrun else '',
            ', %d results ignored' % ignored if ignored else '',
            ', ' + overload if overload else '',
            format_ms(summarize(list(flow.rtts)), ('median', 'p99', 'max')))

    def add_server(self, server):
        if self.route is not None:
            self.route.add(server)

    def remove_server(self, server):
        if self.route is not None:
            self.route.remove(server)

    def heard(self, server):
        """``server`` answered a probe: a task connection to it stalled in TCP's
        retransmission back-off is made anew (``DirectRoute.heard``), with a line."""
        nodes = self.route.heard(server) if self.route is not None else []
        if nodes:
            rospy.logwarn('robot %d: %s tasks to server %d stalled in TCP retransmission '
                          'back-off (%s): connecting anew', self.robot_id, self.flow.kind,
                          server, ', '.join(nodes))

    def shutdown(self):
        """Stop sending; a task still out is reported failed (each task is reported once,
        also when the robot stops or a newer copy of it takes its name)."""
        self.pacer.stop()
        if self.flow.abandon(STOPPED) and self.report_pub:
            flush(self.report_pub)
        if self.route is not None:
            self.route.shutdown()
