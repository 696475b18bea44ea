"""How long one attempt of a task may take on a server, from that server's round trips."""

import collections
import functools
import threading
from statistics import NormalDist

IQR_SIGMAS = 1.349       # a normal spread's quartiles are this many standard deviations apart
# standard deviations above the mean of a normal spread's ``quantile`` (asked at every tick)
_sigmas = functools.lru_cache(maxsize=8)(NormalDist().inv_cdf)


class AttemptClock(object):
    """Per-server attempt deadlines: ``factor`` x the p99 of the server's last ``keep``
    task round trips, at least ``floor`` s and at most the task ``timeout``; ``first`` s
    (capped by the timeout) while a server has fewer than ``min_samples``.

    ``expected(server)``, when given, is what the robot's estimate says a task there takes
    (round trip + wait + work, s; None: unknown): the deadline is then at least
    ``load_factor`` times that, so that a server that is slow because it is busy, and
    says so, is not taken for dead.

    ``fresh(server)``, when given, is how long after its first send a task's answer from
    that server is still worth having (s; None: unknown): each attempt gives the server
    what is left of it (within the task's deadline) and the server answers busy when its
    queue cannot meet it, so a stale frame is shed there rather than queued; a re-send or
    hedge goes only where the load says it can still be done in time (:meth:`too_busy`)."""

    def __init__(self, timeout, factor=5.0, floor=0.25, first=1.0, keep=100, min_samples=5,
                 expected=None, load_factor=2.0, fresh=None):
        self.timeout, self.factor, self.floor = float(timeout), float(factor), float(floor)
        self.first, self.keep, self.min_samples = float(first), keep, min_samples
        self.expected, self.load_factor, self.fresh = expected, float(load_factor), fresh
        self._lock = threading.Lock()
        self._rtts = collections.defaultdict(lambda: collections.deque(maxlen=self.keep))

    def add(self, server, rtt):
        with self._lock:
            self._rtts[server].append(rtt)

    def seconds(self, server):
        with self._lock:
            rtts = sorted(self._rtts.get(server, ()))
        if len(rtts) < self.min_samples:
            seconds = max(self.floor, self.first)
        else:
            p99 = rtts[min(len(rtts) - 1, int(0.99 * len(rtts)))]
            seconds = max(self.floor, self.factor * p99)
        expected = self.expected(server) if self.expected is not None else None
        if expected is not None:
            seconds = max(seconds, self.load_factor * expected)
        return min(self.timeout, seconds)

    def hedge_seconds(self, server, quantile):
        """How long to wait before a hedged copy of a task on ``server`` goes elsewhere:
        the ``quantile`` of the usual spread of the server's recent round trips plus their
        median (None while it has fewer than ``min_samples``). A copy takes a round trip
        itself, so one sent as a task passes the quantile seldom beats it: such a task is
        in the tail of the server's usual spread, and hedging it only spent the retry
        budget that a task stuck behind a lost packet (a TCP retransmission, 200 ms or
        more) then lacked. Never less than what the server's load says a task takes there
        (a delay the load explains is no tail, and a copy is twice the work).

        The usual spread is the quartiles' (the quantile of a normal spread of their
        width, above the median), not the round trips' own quantile: the tail a hedge
        cuts stays out of what sets its delay. With the rank quantile a link losing a
        packet in 5 % of tasks set the p95 in the 200 ms tail, hedges stopped, the tail's
        round trips came back into the history and held it there: one simulated field
        had 14 tasks of 150 on that server at 220 ms where a rule hedging them had 4."""
        with self._lock:
            rtts = sorted(self._rtts.get(server, ()))
        if len(rtts) < self.min_samples:
            return None
        median = rtts[len(rtts) // 2]
        # (by nearest rank, lower: one lost packet among a new server's first answers must
        # not make the quartiles' width its own)
        quartiles = rtts[int(0.25 * (len(rtts) - 1))], rtts[int(0.75 * (len(rtts) - 1))]
        spread = (quartiles[1] - quartiles[0]) / IQR_SIGMAS
        seconds = median + _sigmas(quantile) * spread + median
        expected = self.expected(server) if self.expected is not None else None
        return seconds if expected is None else max(seconds, self.load_factor * expected)

    def budget(self, server, remaining, elapsed=0.0):
        """The deadline (s from now) an attempt on ``server`` gives it: the ``remaining``
        time of the task, or less when a fresh answer is wanted sooner (freshness counts
        from the task's first send, ``elapsed`` s ago, not from each attempt)."""
        fresh = self.fresh(server) if self.fresh is not None else None
        return remaining if fresh is None else min(remaining, fresh - elapsed)

    def too_busy(self, server, elapsed=0.0):
        """Whether a task first sent ``elapsed`` s ago, sent to ``server`` now, would be
        answered too late: its freshness is spent, or what is left of it is less than the
        server's load says the task takes there (False when its freshness is unknown)."""
        fresh = self.fresh(server) if self.fresh is not None else None
        if fresh is None:
            return False
        expected = self.expected(server) if self.expected is not None else None
        return fresh - elapsed <= (expected or 0.0)


def from_params(get, kind, period, newest_wins, load=None):
    """The :class:`AttemptClock` of a robot's ``kind`` stream, one task every ``period()`` s,
    from its parameters (``get(name)``), with ``load`` (a load-aware robot's
    :class:`~server_select.core.robot.robot_load.RobotLoad`, or None): a load-aware robot's
    first answers from a server may take half the timeout (its work is not known yet; its
    probes say whether it is up), and a frame (``newest_wins``) is fresh for
    ``~fresh_factor`` x its unqueued time there."""
    timeout, fresh = get('task_timeout'), get('fresh_factor')
    return AttemptClock(timeout, factor=get('retry_factor'), floor=get('retry_floor'),
                        first=timeout / 2.0 if load else 1.0,
                        expected=load.expected(kind) if load else None,
                        fresh=load.fresh_for(kind, fresh, period)
                        if load and newest_wins and fresh > 0 else None)
