"""Answered tasks as latency samples (passive measurement; no rospy).

A task's round trip is the network *and* the server's queueing and work: what the
application really gets. A probe's is the network only. So that the two can share one
window and one ranking, a task's round trip enters it less the work the *fastest* server
needs for a task of its kind: the kind's *baseline*. For each server the robot has sent
tasks to, the median of the recent differences between a task's round trip and that
server's probe latency at the time is its overhead; the baseline is the lowest overhead
of any server. What a slow, loaded or queueing server adds above that is what makes it
rank worse than its probes alone would; on the fastest server a task sample is, on
average, its probe latency (a median: jitter does not bias it). Load-aware probes carry
the server's expected wait and work already; the baseline is then what a task adds to
that on the server where it adds least: the transfer of its payload, which every server's
tasks pay alike.

The overheads are the robot's own and forget: each holds the last ``keep`` differences.
A server loaded from the start, the only one a robot ever used, is not told apart (there
is no faster answer to compare with); it is as soon as the robot has used another one, or
once its load started after more than half of its ``keep`` differences were taken.
"""

import collections
import math
import statistics
import threading

from server_select.core.ranking.window import valid_rtt


class TaskBaseline(object):
    """Per task kind, the work a task adds to a probe round trip on the fastest server."""

    def __init__(self, keep=200, min_count=5):
        if keep < 1 or min_count < 1:
            raise ValueError('keep and min_count must be >= 1, got %r %r' % (keep, min_count))
        self.keep, self.min_count = keep, min_count
        self._differences = {}       # (kind, server) -> deque of task rtt - probe latency

    def overhead(self, kind, server):
        """The median difference of ``server``'s tasks of ``kind`` (None: too few)."""
        differences = self._differences.get((kind, server))
        if differences is None or len(differences) < self.min_count:
            return None
        return statistics.median(differences)

    def baseline(self, kind):
        """The kind's baseline (s): the lowest overhead of any server (None: none known)."""
        known = [self.overhead(k, s) for k, s in list(self._differences) if k == kind]
        known = [o for o in known if o is not None]
        return min(known) if known else None

    def sample(self, kind, server, rtt, probe_latency):
        """Learn from one task of ``kind`` answered by ``server`` after ``rtt`` s
        (``probe_latency``: that server's probe latency now, None if unknown); return the
        latency sample it is (``rtt`` less the baseline, >= 0), or None while no baseline is
        known yet."""
        if probe_latency is None or not (math.isfinite(rtt) and rtt >= 0):
            return None
        differences = self._differences.get((kind, server))
        if differences is None:
            differences = self._differences[(kind, server)] = collections.deque(
                maxlen=self.keep)
        differences.append(rtt - probe_latency)
        base = self.baseline(kind)
        return None if base is None else max(0.0, rtt - base)


class TaskCost(object):
    """What a server's tasks cost above its probes, remembered once the robot has left it
    (``~task_memory``).

    A task sample enters the window for as long as the window lasts; a robot that left a
    loaded server sends it no more tasks, its task samples age out, its probes alone call
    the server near again, and the robot goes back to find it still loaded (the fleet did
    so every few seconds). Here, per (robot, server), each task sample's excess over the
    pair's probe latency (an EWMA of its probes, time constant ``probe_tau`` s) is kept (the
    last ``keep``); a probe sample then enters the window with the median excess added,
    fading as ``exp(-age / tau)`` with the age of the pair's last task sample. So a server
    whose tasks cost more stays ranked by that cost while the robot is away, and is tried
    again once the memory has faded (after about ``tau`` x ln(excess / margin) s), in case
    its load has gone. A median of several: one task that needed a retransmission does not
    make a penalty; only an excess above zero counts (a probe is never made faster).
    """

    def __init__(self, tau, keep=9, min_count=3, probe_tau=1.0):
        if not tau > 0 or keep < 1 or min_count < 1 or not probe_tau > 0:
            raise ValueError('tau and probe_tau must be > 0, keep and min_count >= 1: '
                             '%r %r %r %r' % (tau, keep, min_count, probe_tau))
        self.tau, self.keep, self.min_count, self.probe_tau = tau, keep, min_count, probe_tau
        self._lock = threading.Lock()
        self._probe = {}        # key -> [probe EWMA, time of its last probe]
        self._excess = {}       # key -> [deque of excesses, time of the last task sample]

    def enter(self, key, now, ok, rtt, probe=True):
        """The value a sample of ``key`` enters the window with: a good probe's round trip
        plus the pair's remembered task cost (:meth:`probe`); a task sample (``probe``
        False, learnt by :meth:`task`), a failed or an impossible one as it is (the window
        refuses the impossible)."""
        if not (ok and valid_rtt(rtt)):
            return rtt
        if probe:
            return self.probe(key, now, rtt)
        self.task(key, now, rtt)
        return rtt

    def probe(self, key, now, rtt):
        """A good probe round trip of ``key`` (e.g. (robot, server)) at ``now``: the value
        it enters the window with (``rtt`` plus the pair's remembered task cost)."""
        with self._lock:
            state = self._probe.get(key)
            if state is None:
                self._probe[key] = [rtt, now]
            else:
                weight = 1.0 - math.exp(-max(0.0, now - state[1]) / self.probe_tau)
                state[0] += weight * (rtt - state[0])
                state[1] = now
            return rtt + self._penalty(key, now)

    def task(self, key, now, sample):
        """A task sample of ``key`` (a round trip less the kind's baseline) at ``now``."""
        with self._lock:
            probe = self._probe.get(key)
            if probe is None:
                return              # nothing to compare with yet
            kept = self._excess.get(key)
            if kept is None:
                kept = self._excess[key] = [collections.deque(maxlen=self.keep), now]
            kept[0].append(sample - probe[0])
            kept[1] = now

    def above_probes(self, key, sample):
        """How much a task sample of ``key`` lies above the pair's probe latency (s, >= 0;
        0 while no probe is known): the part of it that is queueing and work, not network."""
        with self._lock:
            probe = self._probe.get(key)
            return max(0.0, sample - probe[0]) if probe is not None else 0.0

    def penalty(self, key, now):
        """What a probe of ``key`` has added to it now (s, >= 0)."""
        with self._lock:
            return self._penalty(key, now)

    def _penalty(self, key, now):
        kept = self._excess.get(key)
        if kept is None or len(kept[0]) < self.min_count:
            return 0.0
        excess = statistics.median(kept[0])
        if excess <= 0.0:
            return 0.0
        return excess * math.exp(-max(0.0, now - kept[1]) / self.tau)

    def forget(self, key):
        """Drop what is known of ``key`` (a server that left)."""
        with self._lock:
            self._probe.pop(key, None)
            self._excess.pop(key, None)
