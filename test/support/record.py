"""What the rostest test nodes record of a fleet: :class:`Topics` (any topics, as they
arrive) and :class:`FleetRecorder` (a fleet's flags, tasks, results, reports and probe
samples, by routing); :func:`until_answered` (a test's first task)."""

import collections
import threading
import time

import rospy
from rospy.numpy_msg import numpy_msg

from server_select.core.config import names
from server_select.core.util.procs import wait_until
from server_select.msg import LatencySample, SelectionFlag, SortResult, SortTask, TaskReport

Received = collections.namedtuple('Received', 'time msg')


class Topics(object):
    """What some topics carry, as it arrives: ``Topics({'flags': ('/server_select_flag',
    SelectionFlag), ...}, buff_size=1 << 24)``; every store keeps ``Received(time, msg)``
    (the receive time by ``clock``: monotonic, or ``rospy.get_time`` to compare with
    stamps), and ``options`` go to every subscriber."""

    def __init__(self, stores, clock=time.monotonic, **options):
        self.lock, self.clock = threading.Lock(), clock
        self._got = dict((name, []) for name in stores)
        options.setdefault('queue_size', 1000)
        self.subs = [rospy.Subscriber(topic, kind, self._add, name, **options)
                     for name, (topic, kind) in sorted(stores.items())]

    def _add(self, msg, name):
        with self.lock:
            self._got[name].append(Received(self.clock(), msg))

    def received(self, name, test=None):
        """The ``Received`` of store ``name`` so far (those whose message passes ``test``)."""
        with self.lock:
            return [r for r in self._got[name] if test is None or test(r.msg)]

    def messages(self, name, test=None):
        """The messages of :meth:`received`."""
        return [r.msg for r in self.received(name, test)]


def until_answered(send, answered, timeout=20.0, period=0.5):
    """Call ``send()`` every ``period`` s until ``answered()`` (True) or ``timeout`` (False).

    A test's first task: connected both ways is not yet wired both ways (a rospy
    publisher adds a subscriber's connection after the subscriber sees it), so a message
    published at once may reach nobody."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not rospy.is_shutdown():
        send()
        if wait_until(answered, period, period=0.02):
            return True
    return False


class FleetRecorder(object):
    """Every flag, task, result and task report (and the probe samples of ``probe_pairs``),
    with its (monotonic) receive time.

    With direct routing (``robots`` and ``servers`` given), tasks are recorded from every
    server's own topic and results from every robot's own topic; what still arrives on
    the broadcast topics is kept apart, in ``broadcast``.
    """

    def __init__(self, robots=(), servers=(), probe_pairs=()):
        self.lock = threading.Lock()
        self.flags, self.tasks, self.results, self.reports = [], [], [], []
        self.broadcast = []
        self.samples = []       # probe samples of ``probe_pairs`` ((robot, server) each)
        direct = bool(robots and servers)
        self.subs = [
            rospy.Subscriber(names.SELECTION_TOPIC, SelectionFlag, self._add, 'flags',
                             tcp_nodelay=True, queue_size=1000),
            rospy.Subscriber(names.SORT_TASK_TOPIC, numpy_msg(SortTask), self._add,
                             'broadcast' if direct else 'tasks', tcp_nodelay=True,
                             queue_size=1000),
            rospy.Subscriber(names.SORT_RESULT_TOPIC, numpy_msg(SortResult), self._add,
                             'broadcast' if direct else 'results', tcp_nodelay=True,
                             queue_size=1000),
            rospy.Subscriber(names.TASK_REPORT_TOPIC, TaskReport, self._add, 'reports',
                             tcp_nodelay=True, queue_size=1000),
        ]
        self.subs += [rospy.Subscriber(names.sample_topic(r, s), LatencySample, self._add,
                                       'samples', tcp_nodelay=True, queue_size=1000)
                      for r, s in probe_pairs]
        if direct:
            self.subs += [rospy.Subscriber(names.server_topic(s, names.SORT_TASK_TOPIC),
                                           numpy_msg(SortTask), self._add, 'tasks',
                                           tcp_nodelay=True, queue_size=1000) for s in servers]
            self.subs += [rospy.Subscriber(names.robot_topic(r, names.SORT_RESULT_TOPIC),
                                           numpy_msg(SortResult), self._add, 'results',
                                           tcp_nodelay=True, queue_size=1000) for r in robots]

    def _add(self, msg, store):
        with self.lock:
            getattr(self, store).append(Received(time.monotonic(), msg))

    def snapshot(self, store):
        with self.lock:
            return list(store)

    def latest_flags(self):
        """{robot_id: last SelectionFlag}."""
        return dict((r.msg.robot_id, r.msg) for r in self.snapshot(self.flags))

    def reports_of(self, robot_id):
        return [r.msg for r in self.snapshot(self.reports) if r.msg.robot_id == robot_id]

    @staticmethod
    def wait_for(condition, timeout):
        """Poll ``condition()`` until it is true (return True) or ``timeout`` s pass."""
        return wait_until(condition, timeout)
