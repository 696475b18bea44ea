"""Answered tasks as latency samples (passive measurement; no rospy).

A task's round trip is the network *and* the server's queueing and work: what the
application really gets. A probe's is the network only. So that the two can share one
window and one ranking, a task's round trip enters it less the work any server needs for a
task of its kind: the kind's *baseline*, a low quantile of the recent differences between
a task's round trip and its server's probe latency at the time. What a slow, loaded or
queueing server adds above that baseline is what makes it rank worse than its probes
alone would; on an idle server a task sample is about its probe latency.

The baseline is learned from the robot's own answers (any server) and forgets: it holds
the last ``keep`` differences per kind. A server loaded from the start, the only one a
robot ever used, is not told apart (there is no unloaded answer to compare with); it is as
soon as the robot has used another one.
"""

import collections
import math


class TaskBaseline(object):
    """Per task kind, the work a task adds to a probe round trip on an idle path."""

    def __init__(self, keep=200, quantile=0.1, min_count=5):
        if not 0 <= quantile < 1 or keep < 1 or min_count < 1:
            raise ValueError('keep >= 1, min_count >= 1 and 0 <= quantile < 1, got %r %r %r'
                             % (keep, min_count, quantile))
        self.keep, self.quantile, self.min_count = keep, quantile, min_count
        self._differences = {}

    def baseline(self, kind):
        """The kind's baseline (s), or None while fewer than ``min_count`` are known."""
        differences = self._differences.get(kind)
        if differences is None or len(differences) < self.min_count:
            return None
        ordered = sorted(differences)
        return ordered[int(math.floor(self.quantile * (len(ordered) - 1)))]

    def sample(self, kind, rtt, probe_latency):
        """Learn from one answered task of ``kind`` (``rtt`` s; ``probe_latency``: its
        server's probe latency now, None if unknown); return the latency sample it is
        (``rtt`` less the baseline, at least ``probe_latency``'s floor of 0), or None while
        the baseline is still being learned."""
        if probe_latency is None or not (math.isfinite(rtt) and rtt >= 0):
            return None
        differences = self._differences.get(kind)
        if differences is None:
            differences = self._differences[kind] = collections.deque(maxlen=self.keep)
        differences.append(rtt - probe_latency)
        base = self.baseline(kind)
        return None if base is None else max(0.0, rtt - base)
