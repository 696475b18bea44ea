"""ROS wiring of one task stream of a robot (its logic: core.robot.stream).

Like tf2_ros's ``TransformListener``, :class:`TaskStream` only owns the publishers,
subscribers and its pacing thread, and forwards into the robot's stream.
"""

import math

import rospy

from server_select.core.config import names
from server_select.core.util.pacer import Pacer
from server_select.core.util.stats import format_ms, summarize
from server_select.core.flow.outcome import STOPPED, cut_off
from server_select.core.flow.task_flow import ENDED, OUTRUN, RETRIED
from server_select.msg import TaskReport
from server_select.core.util.lasting import Lasting
from server_select.ros.graph import hearing, publisher_of, subscribers, unheard
from server_select.ros.senders import SenderGate
from server_select.ros.node import fleet, flush
from server_select.ros.routing import DEAF_GRACE, BroadcastRoute, made_anew
from server_select.ros.seal import SealedPublisher


class TaskStream(object):
    """The wire of ``core`` (a :class:`~server_select.core.robot.stream.Stream` of robot
    ``robot_id``): its task and result topics (``route``; none when the robot works
    ``local``ly), its ``task_report``s, and the thread that paces it.

    Before the first task the stream waits until every node of ``listeners`` (a recorder
    that must see every task) hears its task reports, and its tasks where it subscribes to
    them, and until its task and result topics reach a server; a listener that subscribes
    to the reports (as the master says) and has not been connected for DEAF_GRACE s gets
    the report publisher made anew (rospy's subscriber connects once: a connection lost as
    it was made left a robot waiting for good). A result counts only if the
    node ``expected_publisher(server, refresh)`` names published it (a
    :class:`~server_select.ros.senders.SenderGate`).

    One thread paces the stream (a :class:`~server_select.core.util.pacer.Pacer`): it
    wakes when the stream's ``next_time`` comes and when a result changes what is due;
    between those it sleeps (a timer polling at 50 Hz cost a robot about 1 % of this
    host's core by itself).
    """

    def __init__(self, robot_id, core, local=False, expected_publisher=None,
                 route=BroadcastRoute, listeners=()):
        self.robot_id, self.core, self.flow = robot_id, core, core.flow
        self.kind = core.kind
        self.listeners = list(listeners)
        self.senders = SenderGate('robot %d' % robot_id, 'server {key}',
                                  lookup=expected_publisher)
        self.route = None if local else route(robot_id, self.kind, self.on_result)
        self.node_of = expected_publisher
        self.report_pub = None
        self._deaf = Lasting(DEAF_GRACE)
        self.pacer = Pacer(self._act, core.next_time, name='%s tasks' % self.kind.kind,
                           on_error=self._on_error)

    def start(self):
        """Its topics; then (:meth:`pace`) its thread, once the robot has started."""
        self.report_pub = self._report_publisher()
        if self.route is not None:
            self.route.start()

    def pace(self):
        self.pacer.start()

    def _act(self):
        if rospy.is_shutdown():
            self.pacer.stop()
            return
        self.core.act()

    def _on_error(self, error):
        rospy.logerr_throttle(5.0, 'robot %d: %s tasks: %s: %s' % (
            self.robot_id, self.flow.kind, type(error).__name__, error))

    def unready(self):
        """What the first task still waits for on the wire ('': nothing)."""
        deaf = self.deaf()
        if deaf:
            return '%s to hear them' % ', '.join(deaf)
        return '' if self.wired() else 'a server'

    def wired(self):
        """Whether the first candidate's task topic and our result topic are connected."""
        candidates = self.flow.candidates()
        return bool(candidates) and self.wired_to(candidates[0])

    def deaf(self):
        """The nodes of ``listeners`` that do not hear our task reports yet, or our tasks
        where they subscribe to them (asked before the first task only)."""
        if not self.listeners:
            return []
        deaf = unheard(self.listeners, self.report_pub, self.route.publishers()
                       if self.route is not None else [], rospy.get_name())
        self._repair_reports(deaf)
        return deaf

    @staticmethod
    def _report_publisher():
        return SealedPublisher(fleet(names.TASK_REPORT_TOPIC), TaskReport, queue_size=100)

    def _repair_reports(self, deaf):
        """The report publisher made anew when a listener that subscribes to it has not
        been connected for DEAF_GRACE s (the master asked once a grace period at most)."""
        missing = [n for n in deaf if n not in hearing(self.report_pub)]
        if not self._deaf.held('reports', bool(missing)):
            return
        listed = subscribers(self.report_pub.resolved_name, rospy.get_name())
        missing = [n for n in missing if n in listed]
        if missing:
            self.report_pub, _ = made_anew(self.report_pub, self._report_publisher, missing)
            rospy.logwarn_throttle(60.0, 'robot %d: %s subscribe to our task reports and have '
                                   'not heard them for %g s: publishing them anew'
                                   % (self.robot_id, ', '.join(missing), DEAF_GRACE))

    def wired_to(self, server):
        """Whether our task topic reaches ``server`` (and our result topic hears one)."""
        return self.route is None or self.route.wired(
            server, self.node_of(server) if self.node_of else None)

    def publish(self, request, server, budget):
        """A task to ``server``; ``budget``: what it is told it has (None: nothing)."""
        request.server_id = server
        if budget is not None and hasattr(request, 'budget'):
            request.budget = budget
        self.route.publish(request, server)

    def on_result(self, result):
        if result.robot_id != self.robot_id:
            return
        if not self.senders.admits(result, lambda: 'a %s result for task %d claiming server '
                                   '%d' % (self.flow.kind, result.task_id, result.server_id),
                                   result.server_id):
            return
        busy = bool(getattr(result, 'busy', False))
        status = self.core.resolve(result.task_id, result.server_id, result.ok, result.error,
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

    def report(self, outcome):
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
        retransmission back-off, or never made, is made anew (``BroadcastRoute.heard``,
        ``DirectRoute.heard``), with a line."""
        if self.route is None:
            return
        nodes = self.route.heard(server, self.node_of(server) if self.node_of else None)
        if nodes:
            rospy.logwarn('robot %d: %s tasks to server %d not heard by %s (a connection '
                          'stalled in TCP retransmission back-off, or never made): '
                          'connecting anew', self.robot_id, self.flow.kind, server,
                          ', '.join(nodes))

    def shutdown(self):
        """Stop sending; a task still out is reported failed (each task is reported once,
        also when the robot stops or a newer copy of it takes its name)."""
        self.pacer.stop()
        if self.flow.abandon(STOPPED) and self.report_pub:
            flush(self.report_pub)
        if self.route is not None:
            self.route.shutdown()
