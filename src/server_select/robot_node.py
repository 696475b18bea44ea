"""Robot: probes every server, follows the manager's selection and sends sort tasks."""

import concurrent.futures
import itertools
import threading
import time

import numpy as np
import rospy
from rospy.numpy_msg import numpy_msg

from server_select import names
from server_select.msg import LatencySample, SelectionFlag, SortResult, SortTask, TaskReport
from server_select.node_util import get_param, run
from server_select.params import (parse_fixed_server, parse_id, parse_id_list, parse_mode,
                                  parse_non_negative, parse_positive)
from server_select.probe_client import TimedServiceProxy
from server_select.sort_task import check_sorted, fingerprint, make_values
from server_select.srv import LatencyProbe, LatencyProbeRequest
from server_select.stats import format_ms, summarize
from server_select.tracker import NONE, TaskTracker


class RobotNode(object):
    """A robot of the fleet.

    Probing: every ``1/~probe_rate`` s each server's ``latency_S<s>`` is called over a
    persistent connection, each server from its own worker thread, each call bounded by
    ``~probe_timeout``; a server whose previous probe is still running gets a failed
    sample instead of a second call. Every sample, failed ones too, is published.

    Tasks: ``~task_size`` random int32 values at ``~task_rate``, addressed to the selected
    server (``~mode`` ``select``) or to ``~fixed_server`` (``fixed``, the paper's baseline).
    Each task ends in exactly one ``task_report``: a checked result, an error result, or a
    timeout after ``~task_timeout``.

    :ROS Parameters:
        - ``~robot_id`` (int, required)
        - ``~servers`` (list of int, required): servers to probe.
        - ``~mode`` (str, ``select``): ``select`` or ``fixed``.
        - ``~fixed_server`` (int, first of ``~servers``): target in fixed mode.
        - ``~probe_rate`` (Hz, 1.0), ``~probe_timeout`` (s, 0.5)
        - ``~task_rate`` (Hz, 2.0), ``~task_size`` (int, 1000), ``~task_timeout`` (s, 2.0)
        - ``~tasks`` (int, 0): stop after this many tasks (0: never).
        - ``~start_delay`` (s, 0.0): wait this long before the first task, e.g. for a
          recorder (rosbag, a test) to connect: rospy drops messages sent before that.
        - ``~summary_period`` (s, 10.0): period of the log summary.
        - ``~seed`` (int, robot_id): task data random seed.
    :ROS Publishers:
        - ``latency_R<robot_id>S<s>`` (server_select/LatencySample), one topic per server.
        - ``data`` (server_select/SortTask)
        - ``task_report`` (server_select/TaskReport)
    :ROS Subscribers:
        - ``server_select_flag`` (server_select/SelectionFlag)
        - ``processed_data`` (server_select/SortResult)
    :ROS Services called:
        - ``latency_S<s>`` (server_select/LatencyProbe)
    """

    def __init__(self):
        self.robot_id = parse_id('~robot_id', get_param('~robot_id'))
        self.servers = parse_id_list('~servers', get_param('~servers'))
        self.mode = parse_mode('~mode', get_param('~mode', 'select'))
        self.fixed_server = parse_fixed_server(
            '~fixed_server', get_param('~fixed_server', self.servers[0]), self.servers, self.mode)
        self.probe_rate = parse_positive('~probe_rate', get_param('~probe_rate', 1.0))
        self.probe_timeout = parse_positive('~probe_timeout', get_param('~probe_timeout', 0.5))
        self.task_rate = parse_positive('~task_rate', get_param('~task_rate', 2.0))
        self.task_size = parse_positive('~task_size', get_param('~task_size', 1000), integer=True)
        task_timeout = parse_positive('~task_timeout', get_param('~task_timeout', 2.0))
        tasks = get_param('~tasks', 0)
        self.task_limit = 0 if tasks in (0, '0') else parse_positive('~tasks', tasks, integer=True)
        summary_period = parse_positive('~summary_period', get_param('~summary_period', 10.0))
        seed = parse_id('~seed', get_param('~seed', self.robot_id))
        start_delay = parse_non_negative('~start_delay', get_param('~start_delay', 0.0))
        self._start_after = time.monotonic() + start_delay

        self._rng = np.random.default_rng(seed)
        self._lock = threading.Lock()
        self._selected = NONE
        self._selection_seen = False
        self._switches = 0
        self._task_ids = itertools.count(1)
        self._sent = 0
        self._rtts = []
        self._failed = 0
        self._started = False
        self.tracker = TaskTracker(task_timeout)

        self.sample_pubs = dict(
            (s, rospy.Publisher(names.sample_topic(self.robot_id, s), LatencySample, queue_size=10))
            for s in self.servers)
        self.task_pub = rospy.Publisher(names.SORT_TASK_TOPIC, numpy_msg(SortTask), queue_size=100)
        self.report_pub = rospy.Publisher(names.TASK_REPORT_TOPIC, TaskReport, queue_size=100)
        self.flag_sub = rospy.Subscriber(names.SELECTION_TOPIC, SelectionFlag, self.on_flag,
                                         queue_size=100, tcp_nodelay=True)
        self.result_sub = rospy.Subscriber(names.SORT_RESULT_TOPIC, numpy_msg(SortResult),
                                           self.on_result, queue_size=100, tcp_nodelay=True,
                                           buff_size=1 << 24)

        self.proxies = dict(
            (s, TimedServiceProxy(names.probe_service(s), LatencyProbe)) for s in self.servers)
        self._probe_seq = itertools.count(1)
        self._probe_pool = concurrent.futures.ThreadPoolExecutor(
            max_workers=len(self.servers), thread_name_prefix='probe')
        self._inflight = {}
        self._probe_ok = set()

        self.probe_timer = rospy.Timer(rospy.Duration(1.0 / self.probe_rate), self.on_probe_timer)
        self.task_timer = rospy.Timer(rospy.Duration(1.0 / self.task_rate), self.on_task_timer)
        self.expire_timer = rospy.Timer(rospy.Duration(0.05), self.on_expire_timer)
        self.summary_timer = rospy.Timer(rospy.Duration(summary_period), self.on_summary_timer)
        rospy.on_shutdown(self.on_shutdown)
        rospy.loginfo('robot %d: mode %s%s, probing servers %s at %.3g Hz',
                      self.robot_id, self.mode,
                      ' (server %d)' % self.fixed_server if self.mode == 'fixed' else '',
                      self.servers, self.probe_rate)

    # -- probing ---------------------------------------------------------------------------

    def on_probe_timer(self, _event):
        if rospy.is_shutdown():
            return
        for server in self.servers:
            previous = self._inflight.get(server)
            if previous is not None and not previous.done():
                self._publish_sample(server, next(self._probe_seq), rospy.Time.now(), None,
                                     'previous probe still in progress')
                continue
            try:
                self._inflight[server] = self._probe_pool.submit(
                    self._probe, server, next(self._probe_seq))
            except RuntimeError:  # pool shut down: the node is stopping
                return

    def _probe(self, server, seq):
        stamp = rospy.Time.now()
        request = LatencyProbeRequest(robot_id=self.robot_id, seq=seq, stamp=stamp)
        try:
            response, rtt = self.proxies[server].call_within(request, self.probe_timeout)
        except rospy.ServiceException as error:
            self._publish_sample(server, seq, stamp, None, str(error))
            return
        if response.server_id != server or response.seq != seq:
            self._publish_sample(server, seq, stamp, None, 'answer from server %d seq %d'
                                 % (response.server_id, response.seq))
            return
        self._publish_sample(server, seq, stamp, rtt, '')
        self._probe_ok.add(server)

    def _publish_sample(self, server, seq, stamp, rtt, error):
        sample = LatencySample(robot_id=self.robot_id, server_id=server, seq=seq,
                               ok=rtt is not None, rtt=rtt or 0.0, error=error)
        sample.header.stamp = stamp
        if error:
            rospy.logdebug('robot %d: probe of server %d failed: %s', self.robot_id, server, error)
        self.sample_pubs[server].publish(sample)

    # -- selection -------------------------------------------------------------------------

    def on_flag(self, flag):
        if flag.robot_id != self.robot_id:
            return
        with self._lock:
            self._selection_seen = True
            if flag.server_id != self._selected:
                if self._selected != NONE:
                    self._switches += 1
                rospy.loginfo('robot %d: selected server %s (ranking %s)', self.robot_id,
                              flag.server_id if flag.server_id != NONE else 'none',
                              list(flag.ranking))
                self._selected = flag.server_id

    def target(self):
        """The server a task sent now goes to (NONE when there is none)."""
        if self.mode == 'fixed':
            return self.fixed_server
        with self._lock:
            return self._selected

    def _ready(self):
        """Tasks start once the target is known to answer and the task topics are wired."""
        if time.monotonic() < self._start_after:
            return False
        if self.mode == 'fixed':
            target_up = self.fixed_server in self._probe_ok
        else:
            with self._lock:
                target_up = self._selection_seen and self._selected != NONE
        return (target_up and self.task_pub.get_num_connections() > 0
                and self.result_sub.get_num_connections() > 0)

    # -- tasks -----------------------------------------------------------------------------

    def on_task_timer(self, _event):
        if self.task_limit and self._sent >= self.task_limit:
            return
        if not self._started:
            if not self._ready():
                rospy.loginfo_throttle(5.0, 'robot %d: waiting for a server before sending tasks'
                                       % self.robot_id)
                return
            self._started = True
            rospy.loginfo('robot %d: sending tasks of %d values at %.3g Hz',
                          self.robot_id, self.task_size, self.task_rate)
        self.send_task()

    def send_task(self):
        task_id = next(self._task_ids)
        self._sent += 1
        target = self.target()
        stamp = rospy.Time.now()
        if target == NONE:
            self._report(self.tracker.fail(task_id, time.perf_counter(), NONE,
                                           'no server selected'), stamp)
            return
        values = make_values(self._rng, self.task_size)
        task = SortTask(robot_id=self.robot_id, task_id=task_id, server_id=target, data=values)
        task.header.stamp = stamp
        self.tracker.sent(task_id, time.perf_counter(), target, (fingerprint(values), stamp))
        self.task_pub.publish(task)

    def on_result(self, result):
        if result.robot_id != self.robot_id:
            return
        now = time.perf_counter()
        context = self.tracker.context(result.task_id)
        error = result.error
        if context is not None and result.ok:
            error = check_sorted(result.data, context[0]) or ''
        outcome = self.tracker.resolve(result.task_id, now, result.server_id,
                                       result.ok and not error, error)
        if outcome is None:
            rospy.logwarn('robot %d: result for task %d from server %d is a duplicate or '
                          'arrived after its timeout', self.robot_id, result.task_id,
                          result.server_id)
            return
        if outcome.answered_by != outcome.server_id:
            rospy.logwarn('robot %d: task %d sent to server %d was answered by server %d',
                          self.robot_id, result.task_id, outcome.server_id, outcome.answered_by)
        self._report(outcome, context[1])

    def on_expire_timer(self, _event):
        for outcome in self.tracker.expire(time.perf_counter()):
            self._report(outcome, None)

    def _report(self, outcome, stamp):
        report = TaskReport(robot_id=self.robot_id, task_id=outcome.task_id, kind='sort',
                            server_id=outcome.server_id, answered_by=outcome.answered_by,
                            ok=outcome.ok, error=outcome.error, rtt=outcome.rtt)
        if stamp is not None:
            report.header.stamp = stamp
        with self._lock:
            if outcome.ok:
                self._rtts.append(outcome.rtt)
            else:
                self._failed += 1
        if not outcome.ok:
            rospy.logerr('robot %d: task %d (server %d) failed: %s', self.robot_id,
                         outcome.task_id, outcome.server_id, outcome.error)
        self.report_pub.publish(report)

    # -- reporting -------------------------------------------------------------------------

    def summary(self):
        with self._lock:
            rtts = list(self._rtts)
            failed, switches, selected = self._failed, self._switches, self._selected
        return ('robot %d: %d tasks sent, %d ok, %d failed, %d pending; task round trip %s; '
                'server %s, %d switches' % (
                    self.robot_id, self._sent, len(rtts), failed, len(self.tracker),
                    format_ms(summarize(rtts), ('median', 'p99', 'max')),
                    self.target() if self.target() != NONE else 'none', switches))

    def on_summary_timer(self, _event):
        rospy.loginfo(self.summary())

    def on_shutdown(self):
        for timer in (self.probe_timer, self.task_timer, self.expire_timer, self.summary_timer):
            timer.shutdown()
        self._probe_pool.shutdown(wait=False)
        for proxy in self.proxies.values():
            proxy.close()
        rospy.loginfo(self.summary())


def main():
    run('robot', RobotNode)
