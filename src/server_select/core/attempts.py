"""How long one attempt of a task may take on a server, from that server's round trips."""

import collections
import threading


class AttemptClock(object):
    """Per-server attempt deadlines: ``factor`` x the p99 of the server's last ``keep``
    task round trips, at least ``floor`` s and at most the task ``timeout``; ``first`` s
    (capped by the timeout) while a server has fewer than ``min_samples``.

    ``expected(server)``, when given, is what the server's load says a task there takes
    (round trip + backlog + work, s; None: unknown): the deadline is then at least
    ``load_factor`` times that, so that a server that is slow because it is busy, and
    says so, is not taken for dead."""

    def __init__(self, timeout, factor=5.0, floor=0.25, first=1.0, keep=100, min_samples=5,
                 expected=None, load_factor=2.0):
        self.timeout, self.factor, self.floor = float(timeout), float(factor), float(floor)
        self.first, self.keep, self.min_samples = float(first), keep, min_samples
        self.expected, self.load_factor = expected, float(load_factor)
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
        """The ``quantile`` of the server's recent round trips (None while it has fewer than
        ``min_samples``), and at least what its load says a task takes (a delay the load
        explains is no tail to hedge against, and a copy is twice the work): how long to
        wait before a hedged copy goes elsewhere."""
        with self._lock:
            rtts = sorted(self._rtts.get(server, ()))
        if len(rtts) < self.min_samples:
            return None
        seconds = rtts[min(len(rtts) - 1, int(quantile * len(rtts)))]
        expected = self.expected(server) if self.expected is not None else None
        return seconds if expected is None else max(seconds, self.load_factor * expected)
