"""What the fault tests drive: a demo fleet under roslaunch, and a recorder of its topics."""

import collections
import os
import signal
import subprocess
import threading
import time

import rospy
from rosgraph_msgs.msg import Log

from server_select.core.config import names
from server_select.core.util.procs import stop_group, wait_until
from server_select.msg import SelectionFlag, TaskReport
from server_select.ros.graph import node_pid, publisher_of

Received = collections.namedtuple('Received', 'time msg sender')
NODES = ('/manager', '/server1', '/server2', '/server3', '/robot1', '/robot2')


class Recorder(object):
    """Task reports, flags and log lines of the fleet, with receive times (monotonic)."""

    def __init__(self):
        self.lock = threading.Lock()
        self.reports, self.flags, self.logs = [], [], []
        self.subs = [
            rospy.Subscriber(names.TASK_REPORT_TOPIC, TaskReport, self._add, self.reports,
                             queue_size=10000, tcp_nodelay=True),
            rospy.Subscriber(names.SELECTION_TOPIC, SelectionFlag, self._add, self.flags,
                             queue_size=10000, tcp_nodelay=True),
            rospy.Subscriber('/rosout', Log, self._add, self.logs, queue_size=10000)]

    def _add(self, msg, store):
        with self.lock:
            store.append(Received(time.monotonic(), msg, publisher_of(msg)))

    def clear(self):
        with self.lock:
            for store in (self.reports, self.flags, self.logs):
                del store[:]

    def of(self, store, robot=None, since=0.0):
        with self.lock:
            return [r for r in store if r.time >= since
                    and (robot is None or getattr(r.msg, 'robot_id', robot) == robot)]

    def failures(self, robot):
        """Robot ``robot``'s failed tasks (receive time, id, error) and its warnings, for a
        failing test's message."""
        failed = [(round(r.time, 2), r.msg.task_id, r.msg.error)
                  for r in self.of(self.reports, robot) if not r.msg.ok]
        with self.lock:
            warned = [(round(r.time, 2), r.msg.msg) for r in self.logs
                      if r.msg.name == '/robot%d' % robot and r.msg.level >= Log.WARN]
        return {'failed': failed, 'warnings': warned[-15:]}

    def log_lines(self, node, text):
        with self.lock:
            return [r.msg.msg for r in self.logs if r.msg.name == node and text in r.msg.msg]

    def outcomes(self, robots, timeout):
        """``{robot: counts}`` of the robots' tasks so far (tasks, failed, never answered,
        duplicates, errors), once every task up to the last reported one has had
        ``timeout`` to be reported: a task's report, or a second one, may come that late
        (an observation window, one for all the robots)."""
        last = dict((robot, max((r.msg.task_id for r in self.of(self.reports, robot)),
                                default=0)) for robot in robots)
        time.sleep(timeout + 0.5)
        return dict((robot, self._counts(robot, last[robot])) for robot in robots)

    def _counts(self, robot, last):
        return counts([r.msg for r in self.of(self.reports, robot) if r.msg.task_id <= last],
                      last)


def counts(reports, last=None):
    """Counts of one robot run's task reports (its task ids count from 1): tasks (up to
    ``last``, None: the highest id reported), failed, never answered, duplicates, errors."""
    last = max((m.task_id for m in reports), default=0) if last is None else last
    seen = collections.Counter(m.task_id for m in reports)
    failed = [m for m in reports if not m.ok]
    return {'tasks': last,
            'failed': len(failed),
            'never answered': sum(1 for i in range(1, last + 1) if seen[i] == 0),
            'duplicates': sum(1 for n in seen.values() if n > 1),
            'errors': collections.Counter(m.error.split(' (')[0] for m in failed)}


def _tail(path, lines=15):
    with open(path, errors='replace') as stream:
        return ''.join(collections.deque(stream, lines))


def _kill(pid, sig):
    try:
        os.kill(pid, sig)
    except ProcessLookupError:
        pass


class Fleet(object):
    """``demo.launch`` with ``args`` (3 servers, 2 robots by default), under one roslaunch;
    each robot's first task waits until this node hears its task reports."""

    def __init__(self, log, **args):
        self.log, self.args = log, dict({'report_listeners': rospy.get_name()}, **args)
        self.extra = []
        self.signalled = set()   # pids: a stopped node cannot tell its pid any more

    def __enter__(self):
        with open(self.log, 'a') as stream:
            self.proc = subprocess.Popen(
                ['roslaunch', 'server_select', 'demo.launch', 'output:=log']
                + ['%s:=%s' % kv for kv in sorted(self.args.items())],
                stdout=stream, stderr=subprocess.STDOUT, start_new_session=True)
        if not wait_until(lambda: all(self.pid(n) for n in NODES), 60.0, period=0.5):
            missing = [n for n in NODES if not self.pid(n)]
            # a launch left running would start its stragglers under the next fleet's names
            self.__exit__(None, None, None)
            raise AssertionError('the fleet did not come up in 60 s: %s not registered '
                                 '(%s; its last lines:\n%s)'
                                 % (', '.join(missing), self.log, _tail(self.log)))
        return self

    def __exit__(self, *exc):
        for pid in self.signalled:
            _kill(pid, signal.SIGCONT)
        for proc in self.extra:
            stop_group(proc)
        stop_group(self.proc)
        # Nothing of this fleet may outlive it: a straggler registering under a fleet name
        # would shut down the next fleet's node of that name.
        for node in NODES:
            pid = self.pid(node)
            if pid is not None:
                os.kill(pid, signal.SIGKILL)
        for pid in self.signalled:
            _kill(pid, signal.SIGKILL)
        assert wait_until(lambda: not any(self.pid(n) for n in NODES), 10.0)
        return False

    @staticmethod
    def pid(node):
        try:
            return node_pid(node, rospy.get_name())
        except Exception:  # not registered (yet), or the master is away
            return None

    def signal(self, node, sig):
        """Send ``sig`` to ``node``; returns its pid (kept: whatever happens, the node is
        continued and killed when the fleet ends)."""
        pid = self.pid(node)
        assert pid is not None, '%s is not registered' % node
        self.signalled.add(pid)
        os.kill(pid, sig)
        return pid

    def start(self, *argv):
        """Start one more process (a node run by hand); stopped with the fleet."""
        with open(self.log, 'a') as stream:
            self.extra.append(subprocess.Popen(list(argv), stdout=stream,
                                               stderr=subprocess.STDOUT,
                                               start_new_session=True))
        return self.extra[-1]

    def restart_server(self, server):
        return self.start('rosrun', 'server_select', 'server', '_server_id:=%d' % server,
                          '__name:=server%d' % server)

    def restart_robot(self, robot):
        rate = ['_task_rate:=%s' % self.args['task_rate']] if 'task_rate' in self.args else []
        return self.start('rosrun', 'server_select', 'robot', '_robot_id:=%d' % robot,
                          '_servers:=1,2,3', '__name:=robot%d' % robot, *rate,
                          '_report_listeners:=%s' % rospy.get_name(),
                          *['_%s:=%s' % (k, self.args[k]) for k in ('fleet_key', 'hysteresis')
                            if k in self.args])

    def restart_manager(self):
        return self.start('rosrun', 'server_select', 'manager', '_robots:=1,2',
                          '_servers:=1,2,3', '__name:=manager',
                          '_hysteresis:=%s' % self.args.get('hysteresis', 0.0),
                          '_fleet_key:=%s' % self.args.get('fleet_key', ''))


def kill(fleet, node):
    fleet.signal(node, signal.SIGKILL)
