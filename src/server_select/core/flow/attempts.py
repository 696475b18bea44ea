"""A task's attempts at the robot: the task in flight (:class:`Pending`) and how long one
attempt may take on a server (:class:`AttemptClock`, from that server's round trips and
the robot's estimate of its load)."""

import collections
import functools
import threading
from statistics import NormalDist

from server_select.core.flow.outcome import NO_SERVER, Outcome

IQR_SIGMAS = 1.349       # a normal spread's quartiles are this many standard deviations apart
# standard deviations above the mean of a normal spread's ``quantile`` (asked at every tick)
_sigmas = functools.lru_cache(maxsize=8)(NormalDist().inv_cdf)


class Pending(object):
    """A task in flight: its request, check context, and the attempts made so far."""
    __slots__ = ('task_id', 'stamp', 'request', 'context', 'started', 'attempts', 'deadline',
                 'hedged', 'open', 'not_resent')

    def __init__(self, task_id, stamp, request, context, started):
        self.task_id, self.stamp, self.request, self.context = task_id, stamp, request, context
        self.started, self.attempts, self.deadline = started, [], started
        self.hedged = False
        self.not_resent = None  # why its last failed attempt went nowhere else (None: it did)
        self.open = set()       # servers of attempts not ended yet (no answer, no deadline)

    def attempt(self, server, now, observer=None, kind=None, order=None):
        """An attempt at ``server``, chosen from ``order``, starts ``now``
        (``observer.started(server, kind, first, order)``: ``first`` for the task's first
        attempt)."""
        self.attempts.append((server, now))
        self.open.add(server)
        if observer is not None:
            observer.started(server, kind, len(self.attempts) == 1, order)

    def end(self, server, rtt=None, observer=None):
        """The attempt at ``server`` ended, once: ``observer.ended(server, rtt)``; None
        for every attempt still open."""
        for each in list(self.open) if server is None else [server]:
            if each in self.open:
                self.open.discard(each)
                if observer is not None:
                    observer.ended(each, rtt)

    def hedge_due(self, now, delay):
        """Whether a hedged copy of this task goes now: once, when its only attempt is
        older than ``delay(server)`` s (None: not known yet); a task re-sent meanwhile
        is not hedged."""
        if self.hedged:
            return False
        first, sent = self.attempts[0]
        if len(self.attempts) == 1:
            wait = delay(first)
            if wait is None or now < sent + wait:
                return False
        self.hedged = True
        return len(self.attempts) == 1

    def hedge_at(self, delay):
        """When :meth:`hedge_due` will say yes (None: not by itself: hedged already,
        re-sent, or ``delay`` not known yet)."""
        if self.hedged or len(self.attempts) != 1:
            return None
        first, sent = self.attempts[0]
        wait = delay(first)
        return None if wait is None else sent + wait

    def servers(self):
        """The servers this task was sent to."""
        return frozenset(s for s, _ in self.attempts)

    def sent_at(self, server):
        return next((t for s, t in reversed(self.attempts) if s == server), None)

    def unanswered(self, kind, why):
        """How it ended without an answer: failed, ``why``, the servers it was sent to and,
        when an attempt failed with no other after it, why there was none."""
        return self.outcome(kind, NO_SERVER, False, '%s (%d attempts: servers %s%s)' % (
            why, len(self.attempts), ', '.join(str(s) for s, _ in self.attempts),
            '; not sent again: %s' % self.not_resent if self.not_resent else ''), None)

    def outcome(self, kind, answered_by, ok, error, rtt):
        """How it ended (``rtt`` None: no answer)."""
        return Outcome(self.task_id, kind, self.stamp, self.attempts[0][0], answered_by, ok,
                       error, rtt, len(self.attempts))


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
        self._ordered = {}      # server -> its round trips sorted, until the next one

    def add(self, server, rtt):
        with self._lock:
            self._rtts[server].append(rtt)
            self._ordered.pop(server, None)

    def _sorted(self, server):
        """``server``'s round trips, sorted (asked at each send and each tick: kept)."""
        with self._lock:
            ordered = self._ordered.get(server)
            if ordered is None:
                ordered = self._ordered[server] = sorted(self._rtts.get(server, ()))
            return ordered

    def seconds(self, server):
        rtts = self._sorted(server)
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
        rtts = self._sorted(server)
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
