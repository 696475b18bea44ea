"""Sliding windows of latency samples, one per (robot, server) pair."""

import collections
import math
import threading

Sample = collections.namedtuple('Sample', 'time ok rtt')
PairStats = collections.namedtuple('PairStats', 'mean ok_count failed_count')


def valid_rtt(rtt):
    """Whether ``rtt`` can be a measured round trip: a finite number >= 0."""
    return isinstance(rtt, (int, float)) and not isinstance(rtt, bool) and \
        math.isfinite(rtt) and rtt >= 0


class LatencyWindow(object):
    """The samples of the last ``window`` seconds of every (robot, server) pair.

    Times are those of the caller's clock (the manager's receive time, because robot and
    manager clocks are not shared). Thread-safe: subscriber callbacks add, a timer reads.
    """

    def __init__(self, window):
        if not window > 0:
            raise ValueError('window must be positive, got %r' % (window,))
        self.window = float(window)
        self._lock = threading.Lock()
        self._samples = collections.defaultdict(collections.deque)

    def add(self, robot_id, server_id, now, ok, rtt):
        """Record one sample; failed samples carry no latency. A successful sample whose
        ``rtt`` is not a finite number >= 0 raises ValueError (and is not recorded)."""
        if ok and not valid_rtt(rtt):
            raise ValueError('round trip %r is not a finite number >= 0' % (rtt,))
        with self._lock:
            samples = self._samples[(robot_id, server_id)]
            samples.append(Sample(now, bool(ok), float(rtt) if ok else float('nan')))
            self._prune(samples, now)

    def _prune(self, samples, now):
        horizon = now - self.window
        while samples and samples[0].time <= horizon:
            samples.popleft()

    def stats(self, robot_id, server_id, now):
        """Mean round trip of the successful samples in the window (None when none)."""
        with self._lock:
            samples = self._samples.get((robot_id, server_id))
            if samples is None:
                return PairStats(None, 0, 0)
            self._prune(samples, now)
            rtts = [s.rtt for s in samples if s.ok]
            failed = len(samples) - len(rtts)
        if not rtts:
            return PairStats(None, 0, failed)
        return PairStats(sum(rtts) / len(rtts), len(rtts), failed)

    def robot_stats(self, robot_id, servers, now):
        """``{server_id: PairStats}`` for each of ``servers``."""
        return dict((s, self.stats(robot_id, s, now)) for s in servers)
