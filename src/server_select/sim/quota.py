"""A CPU quota as the kernel's CFS bandwidth control enforces it, for a host with one
worker (no rospy).

A cgroup with ``share`` of a core per ``period`` s may run ``share x period`` s of CPU in
each period, at full speed, and then stops until the next period starts; what it leaves
unused is lost. So a short task on an idle capped host takes its own CPU time, not that
time over the share, and a task that meets a spent quota waits for the next period. The
testbed caps its servers this way (``testbed/cpu.py``, a 100 ms period by default), and a
fluid model (work over share) gets both wrong: it slows every short task by 1/share and
never stalls one.
"""

import math


class CpuQuota(object):
    """The quota of one host: ``share`` (< 1) of a core per ``period`` s, its periods
    starting at ``phase`` s (mod ``period``). :meth:`run` spends it in time order."""

    def __init__(self, share, period, phase=0.0):
        if not 0 < share < 1 or period <= 0:
            raise ValueError('a quota needs a share in (0, 1) and a period > 0, got %r, %r'
                             % (share, period))
        self.share, self.period = float(share), float(period)
        self.phase = float(phase) % self.period
        self.per_period = self.share * self.period
        self._index = None        # the period the quota was last spent in
        self._used = 0.0          # CPU s spent in it

    def _period_of(self, t):
        return int(math.floor((t - self.phase) / self.period))

    def run(self, start, seconds):
        """When ``seconds`` of CPU started at ``start`` end, at full speed while the
        quota lasts; the quota they use is spent. Calls come in time order."""
        t = float(start)
        index = self._period_of(t)
        if self._index is not None:
            index = max(index, self._index)      # a time on a boundary, rounded below it
        while True:
            if index != self._index:
                self._index, self._used = index, 0.0
            end = self.phase + (index + 1) * self.period
            left = min(self.per_period - self._used, end - t)
            if left > 1e-12:
                spent = min(seconds, left)
                self._used += spent
                t += spent
                seconds -= spent
                if seconds <= 1e-12:
                    return t
            index += 1
            t = max(t, end)
