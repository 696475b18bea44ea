"""Sliding windows of latency samples, one per (robot, server) pair.

A pair's latency *statistic* is what a policy ranks by (:data:`STATISTICS`):

- ``mean``: the mean of the window's successful samples (the paper);
- ``median``: their median, and ``trimmed``: their mean without the highest and lowest
  quarter (at least one of each once there are three), so that one probe that needed a
  TCP retransmission cannot reorder a ranking.
"""

import collections
import math
import threading
from statistics import median

STATISTICS = ('mean', 'median', 'trimmed')

Sample = collections.namedtuple('Sample', 'time ok rtt wait')
PairStats = collections.namedtuple('PairStats',
                                   'mean ok_count failed_count value se failed_run wait')
PairStats.__new__.__defaults__ = (None, None, 0, None)
PairStats.__doc__ = """A pair's window: ``mean`` of the successful samples (None: none),
their count, the failed count, ``value`` the window's statistic (None: no successful
sample; of samples that say their *wait* part, load-aware ones, the statistic of the
network part plus the mean wait, the ``mean`` statistic taking the network part's median:
a server short of CPU answers probes late whenever its quota is spent, spikes its tasks
pay in their work already), ``se`` the standard error of the mean (0 with fewer than two
samples; with ``robust``, that of the network part from the median absolute deviation,
which a step in the latency does not inflate, and that of the wait part from the plain
variance: waits are zero most of the time and seconds now and then, which the median
absolute deviation would call no spread at all), ``failed_run`` how many of the newest
samples failed in a row and ``wait`` the mean wait part of load-aware samples (None:
not load-aware)."""

EMPTY = PairStats(None, 0, 0, None, None, 0)


# No round trip this package measures lasts an hour (probes and tasks time out within
# seconds); a larger one is a broken or forged sample, and a few such values would overflow
# a window's running sums to infinity.
MAX_RTT = 3600.0
RTT_RANGE = 'a number of seconds from 0 to %g' % MAX_RTT


def valid_rtt(rtt):
    """Whether ``rtt`` can be a measured round trip: a number from 0 to :data:`MAX_RTT`."""
    return isinstance(rtt, (int, float)) and not isinstance(rtt, bool) and \
        math.isfinite(rtt) and 0 <= rtt <= MAX_RTT


def check_sample(ok, rtt):
    """ValueError for a successful sample whose ``rtt`` is not :data:`RTT_RANGE`."""
    if ok and not valid_rtt(rtt):
        raise ValueError('round trip %r is not %s' % (rtt, RTT_RANGE))


def trimmed_mean(values):
    """The mean of ``values`` without their highest and lowest quarter (at least one each
    from three values on)."""
    values = sorted(values)
    cut = max(1, len(values) // 4) if len(values) >= 3 else 0
    kept = values[cut:len(values) - cut]
    return sum(kept) / len(kept)


def variance_of(values):
    """The sample variance of ``values`` (0 for fewer than two)."""
    n = len(values)
    if n < 2:
        return 0.0
    mean = sum(values) / n
    return sum((v - mean) ** 2 for v in values) / (n - 1)


class _Pair(object):
    """One pair's samples and their running sums (O(1) amortised per sample for the mean;
    the median and trimmed mean cost O(n log n) of the window's n)."""
    __slots__ = ('samples', 'rtt_sum', 'sq_sum', 'ok_count', 'failed_run', 'aware')

    def __init__(self):
        self.samples, self.rtt_sum, self.sq_sum, self.ok_count = collections.deque(), 0.0, 0.0, 0
        self.aware = 0          # successful samples that say their wait part
        self.failed_run = 0

    def append(self, sample):
        self.samples.append(sample)
        self.failed_run = 0 if sample.ok else self.failed_run + 1
        if sample.ok:
            self.rtt_sum += sample.rtt
            self.sq_sum += sample.rtt * sample.rtt
            self.ok_count += 1
            self.aware += sample.wait is not None

    def prune(self, start, keep=0, oldest=None):
        """Drop the samples taken at or before ``start``, but the newest ``keep`` of them
        only when taken at or before ``oldest``."""
        samples, oldest = self.samples, start if oldest is None else oldest
        while samples and samples[0].time <= start and (
                len(samples) > keep or samples[0].time <= oldest):
            old = samples.popleft()
            if old.ok:
                self.ok_count -= 1
                self.rtt_sum -= old.rtt
                self.sq_sum -= old.rtt * old.rtt
                self.aware -= old.wait is not None
        if not self.ok_count:
            self.rtt_sum = self.sq_sum = 0.0     # no rounding residue survives an empty window

    def stats(self, statistic, robust=False):
        failed = len(self.samples) - self.ok_count
        n = self.ok_count
        if not n:
            return PairStats(None, 0, failed, None, None, self.failed_run)
        mean = max(0.0, self.rtt_sum / n)
        variance = max(0.0, self.sq_sum / n - mean * mean) * n / (n - 1) if n > 1 else 0.0
        ok = [s.rtt for s in self.samples if s.ok] if robust or self.aware or statistic in (
            'median', 'trimmed') else None
        if self.aware:          # load-aware samples: the network part and the wait apart
            waits = [s.wait or 0.0 for s in self.samples if s.ok]
            ok = [v - w for v, w in zip(ok, waits)]
        if statistic == 'mean':
            # the network's median (a CPU-capped server answers a probe late whenever
            # its quota is spent: spikes the tasks pay in their work already) + the
            # mean wait
            value = median(ok) + sum(waits) / n if self.aware else mean
        else:
            value = median(ok) if statistic == 'median' else trimmed_mean(ok)
            value += sum(waits) / n if self.aware else 0.0
        if robust and n > 1:    # the network part robust, the queue's plain
            middle = median(ok)
            variance = (1.4826 * median([abs(v - middle) for v in ok])) ** 2
            if self.aware:
                if statistic in ('mean', 'median'):   # ranked by the network's median,
                    variance *= math.pi / 2           # whose error is 1.25 x the mean's
                variance += variance_of(waits)
        return PairStats(mean, n, failed, value, math.sqrt(variance / n),
                         self.failed_run, sum(waits) / n if self.aware else None)


class LatencyWindow(object):
    """The samples of the last ``window`` seconds of every (robot, server) pair.

    Times are those of the caller's clock (the manager's receive time, because robot and
    manager clocks are not shared). Each pair keeps running sums, so adding a sample and
    reading a pair's mean cost O(1) amortised, whatever the number of pairs. ``statistic``
    (one of :data:`STATISTICS`) is the pair's ``value``; ``robust``: standard errors from
    the median absolute deviation (O(n log n) per read). Thread-safe: subscriber callbacks
    add, a timer reads.

    Pairs need not be sampled at one rate (adaptive probing samples contenders often and
    the other servers rarely). The window is a time, the same for every pair: a pair's
    statistic is that of its own samples in it, and its standard error comes from their
    number, so a rarely sampled pair has a wide interval, not a made-up precise one. With
    ``keep`` > 0 a pair sampled less often than ``keep`` times a window also keeps its
    newest ``keep`` samples, up to ``horizon`` s old (at least ``window``): a server
    probed every few seconds stays ranked (by what it last showed, with the error of that
    few) instead of flickering in and out of the ranking between its probes. A sample is
    in the window at time t when t - its time < ``window``, or when it is one of the
    pair's newest ``keep`` and t - its time < ``horizon``.
    """

    def __init__(self, window, statistic='mean', robust=False, keep=0, horizon=None):
        if not window > 0:
            raise ValueError('window must be positive, got %r' % (window,))
        if not (isinstance(keep, int) and keep >= 0):
            raise ValueError('keep must be a count >= 0, got %r' % (keep,))
        # never shorter than the window (e.g. ~window 10 s with ~window_max 8 s)
        horizon = window if horizon is None or not keep else max(window, horizon)
        self.keep, self.horizon = keep, float(horizon)
        if statistic not in STATISTICS:
            raise ValueError('unknown statistic %r (expected one of %s)'
                             % (statistic, ', '.join(STATISTICS)))
        self.window, self.statistic = float(window), statistic
        self.robust = bool(robust)
        self._lock = threading.Lock()
        self._pairs = {}

    def add(self, robot_id, server_id, now, ok, rtt, wait=None, stats=True):
        """Record one sample; failed samples carry no latency. ``wait``: the part of
        ``rtt`` that is the server's wait (a load-aware sample's; None: not said). A
        successful sample whose ``rtt`` is not :data:`RTT_RANGE` raises ValueError (and is
        not recorded).
        Returns whether the pair had a value before, and its :class:`PairStats` after
        (with plain standard errors, which cost nothing: :meth:`stats` gives the robust
        ones; ``stats`` False: None, for a caller that only records)."""
        check_sample(ok, rtt)
        with self._lock:
            pair = self._pairs.get((robot_id, server_id))
            if pair is None:
                pair = self._pairs[(robot_id, server_id)] = _Pair()
            self._prune(pair, now)
            had_value = pair.ok_count > 0
            pair.append(Sample(now, bool(ok), float(rtt) if ok else float('nan'),
                               min(float(wait), float(rtt)) if ok and wait is not None
                               else None))
            return had_value, pair.stats(self.statistic) if stats else None

    def stats(self, robot_id, server_id, now, errors=True):
        """The pair's :class:`PairStats` over the window now (``errors`` False: plain
        standard errors even if the window's are robust, at no cost; ``'robust'``: robust
        ones even if the window's are plain)."""
        with self._lock:
            pair = self._pairs.get((robot_id, server_id))
            if pair is None:
                return EMPTY
            self._prune(pair, now)
            if not pair.samples:       # nothing left: forget the pair
                del self._pairs[(robot_id, server_id)]
            return pair.stats(self.statistic, errors == 'robust' or (self.robust and errors))

    def _prune(self, pair, now):
        pair.prune(now - self.window, self.keep, now - self.horizon)

    def forget_server(self, server_id):
        """Drop every sample of ``server_id`` (a server that left the fleet)."""
        with self._lock:
            for key in [k for k in self._pairs if k[1] == server_id]:
                del self._pairs[key]

    def robot_stats(self, robot_id, servers, now, errors=True):
        """``{server_id: PairStats}`` for each of ``servers``."""
        return dict((s, self.stats(robot_id, s, now, errors)) for s in servers)
