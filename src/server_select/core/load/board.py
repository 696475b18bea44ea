"""What a robot makes of its servers' load reports (no rospy).

A probe answer carries the server's :class:`~server_select.core.load.work_queue.Load`. A robot ranks
servers by expected completion for the tasks it sends: round trip + the mean wait for a
worker + the work (C3, NSDI '15). The mean wait comes from the utilization the server
reports (the other robots' tasks at the rates they arrive), not from its backlog at the
moment of the probe: :func:`queueing`. The backlog, and the robot's own tasks sent since
the report, set an attempt's deadline (:meth:`LoadBoard.expected`).
"""

import collections
import math
import statistics
import threading
import time

# A server whose others' tasks take more than this share of its workers' time is ranked as
# if at this share: past it the queue only grows, and how fast is the deadlines' business.
MAX_UTILIZATION = 0.95
# Probe round trips kept per server for :meth:`LoadBoard.unqueued` (their median: a probe
# of a server short of CPU now and then waits for its next quota period).
RTTS_KEPT = 9


def queueing(utilization, work, workers=1):
    """Mean seconds a task waits for one of ``workers`` workers busy ``utilization`` of the
    time with tasks of ``work`` s each: M/D/c by Sakasegawa's approximation (exact for one
    worker: ``utilization x work / 2 / (1 - utilization)``), the utilization capped at
    ``MAX_UTILIZATION``."""
    rho = min(max(float(utilization), 0.0), MAX_UTILIZATION)
    if rho == 0.0 or work <= 0:
        return 0.0
    c = max(1, int(workers))
    return work * rho ** (math.sqrt(2.0 * (c + 1)) - 1.0) / (c * (1.0 - rho)) / 2.0


class LoadBoard(object):
    """A robot's view of its servers' load: the newest report of each, and its own tasks
    sent to each since (thread-safe).

    ``mix`` is ``{kind: weight}`` of the tasks the robot sends (its streams' rates): the
    *wait* of a server is the mean queueing at its utilization plus the mix's work there,
    what :meth:`wait` adds to a probe's round trip so that servers rank by expected
    completion. A report older than ``max_age`` s counts as none (the probes stopped:
    health decides then). A server that has not yet done a task of a kind is taken to need
    the median of what the others report for it: not nothing, or every robot would rush to
    a server that just came up.
    """

    def __init__(self, mix, max_age=2.0, clock=time.monotonic):
        self.set_mix(mix)
        self.max_age = max_age
        self._clock = clock
        self._lock = threading.Lock()
        self._reports = {}       # server -> [Load, time, tasks sent since]
        self._rtts = {}          # server -> its last probes' round trips

    def set_mix(self, mix):
        """The robot's streams' rates are now ``mix`` (at start, and when one is tuned)."""
        total = float(sum(mix.values()))
        if not mix or not total > 0:
            raise ValueError('mix must give a positive weight to some kind, got %r' % (mix,))
        self.mix = dict((k, w / total) for k, w in mix.items())

    def update(self, server, load, rtt=None):
        """``load``, the newest report of ``server``; ``rtt``, the probe's round trip (s)."""
        with self._lock:
            self._reports[server] = [load, self._clock(), collections.Counter()]
            if rtt is not None:
                self._rtts.setdefault(server, collections.deque(maxlen=RTTS_KEPT)).append(rtt)

    def sent(self, server, kind):
        """One of the robot's tasks went to ``server`` (it is in no report yet)."""
        with self._lock:
            report = self._reports.get(server)
            if report is not None:
                report[2][kind] += 1

    def forget(self, server):
        with self._lock:
            self._reports.pop(server, None)
            self._rtts.pop(server, None)

    def _fresh(self, server):
        report = self._reports.get(server)
        if report is None or self._clock() - report[1] > self.max_age:
            return None
        return report

    def _work(self, load, kind):
        """Seconds of work per ``kind`` task by ``load``, else the others' median."""
        seconds = load.service.get(kind)
        if seconds is not None:
            return seconds
        known = [r[0].service[kind] for r in self._reports.values()
                 if kind in r[0].service and self._clock() - r[1] <= self.max_age]
        return statistics.median(known) if known else 0.0

    def wait(self, server):
        """Mean queueing + the mix's work at ``server`` (s) by its newest report; None:
        none."""
        with self._lock:
            report = self._fresh(server)
            if report is None:
                return None
            load = report[0]
            work = sum(w * self._work(load, k) for k, w in self.mix.items())
            return queueing(load.utilization, work, load.workers) + work

    def expected(self, server, kind):
        """Seconds from a task of ``kind`` reaching ``server`` to its answer leaving it, by
        the newest report's backlog plus the robot's own tasks sent since (None: no fresh
        report)."""
        with self._lock:
            report = self._fresh(server)
            if report is None:
                return None
            load, _, since = report
            extra = sum(self._work(load, k) * n for k, n in since.items())
            return load.backlog + extra / max(1, load.workers) + self._work(load, kind)

    def unqueued(self, server, kind):
        """Seconds a ``kind`` task at ``server`` takes with no queue: the median of its
        last probes' round trips + its work (None: no fresh report, no round trip, or no
        server has done a ``kind`` task yet)."""
        with self._lock:
            report, rtts = self._fresh(server), self._rtts.get(server)
            work = self._work(report[0], kind) if report is not None and rtts else 0.0
            return statistics.median(rtts) + work if work > 0 else None
