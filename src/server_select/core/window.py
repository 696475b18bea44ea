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


class _Pair(object):
    """One pair's samples and their running sums (O(1) amortised per sample)."""
    __slots__ = ('samples', 'rtt_sum', 'ok_count')

    def __init__(self):
        self.samples, self.rtt_sum, self.ok_count = collections.deque(), 0.0, 0

    def append(self, sample):
        self.samples.append(sample)
        if sample.ok:
            self.rtt_sum += sample.rtt
            self.ok_count += 1

    def prune(self, horizon):
        samples = self.samples
        while samples and samples[0].time <= horizon:
            old = samples.popleft()
            if old.ok:
                self.ok_count -= 1
                self.rtt_sum -= old.rtt
        if not self.ok_count:
            self.rtt_sum = 0.0      # no rounding residue survives an empty window

    def stats(self):
        failed = len(self.samples) - self.ok_count
        if not self.ok_count:
            return PairStats(None, 0, failed)
        return PairStats(max(0.0, self.rtt_sum / self.ok_count), self.ok_count, failed)


class LatencyWindow(object):
    """The samples of the last ``window`` seconds of every (robot, server) pair.

    Times are those of the caller's clock (the manager's receive time, because robot and
    manager clocks are not shared). Each pair keeps running sums, so adding a sample and
    reading a pair's mean cost O(1) amortised, whatever the number of pairs. Thread-safe:
    subscriber callbacks add, a timer reads.
    """

    def __init__(self, window):
        if not window > 0:
            raise ValueError('window must be positive, got %r' % (window,))
        self.window = float(window)
        self._lock = threading.Lock()
        self._pairs = {}

    def add(self, robot_id, server_id, now, ok, rtt):
        """Record one sample; failed samples carry no latency. A successful sample whose
        ``rtt`` is not a finite number >= 0 raises ValueError (and is not recorded).
        Returns whether the pair had a mean before, and its :class:`PairStats` after."""
        if ok and not valid_rtt(rtt):
            raise ValueError('round trip %r is not a finite number >= 0' % (rtt,))
        with self._lock:
            pair = self._pairs.get((robot_id, server_id))
            if pair is None:
                pair = self._pairs[(robot_id, server_id)] = _Pair()
            pair.prune(now - self.window)
            had_mean = pair.ok_count > 0
            pair.append(Sample(now, bool(ok), float(rtt) if ok else float('nan')))
            return had_mean, pair.stats()

    def stats(self, robot_id, server_id, now):
        """Mean round trip of the successful samples in the window (None when none)."""
        with self._lock:
            pair = self._pairs.get((robot_id, server_id))
            if pair is None:
                return PairStats(None, 0, 0)
            pair.prune(now - self.window)
            if not pair.samples:       # nothing left: forget the pair
                del self._pairs[(robot_id, server_id)]
            return pair.stats()

    def robot_stats(self, robot_id, servers, now):
        """``{server_id: PairStats}`` for each of ``servers``."""
        return dict((s, self.stats(robot_id, s, now)) for s in servers)
