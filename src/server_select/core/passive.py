"""Answered tasks as latency samples (passive measurement; no rospy).

A task's round trip is the network *and* the server's queueing and work: what the
application really gets. A probe's is the network only. So that the two can share one
window and one ranking, a task's round trip enters it less the work the *fastest* server
needs for a task of its kind: the kind's *baseline*. For each server the robot has sent
tasks to, the median of the recent differences between a task's round trip and that
server's probe latency at the time is its overhead; the baseline is the lowest overhead
of any server. What a slow, loaded or queueing server adds above that is what makes it
rank worse than its probes alone would; on the fastest server a task sample is, on
average, its probe latency (a median: jitter does not bias it).

The overheads are the robot's own and forget: each holds the last ``keep`` differences.
A server loaded from the start, the only one a robot ever used, is not told apart (there
is no faster answer to compare with); it is as soon as the robot has used another one, or
once its load started after more than half of its ``keep`` differences were taken.
"""

import collections
import math
import statistics


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
