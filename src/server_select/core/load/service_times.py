"""What a server's tasks of each kind take (no rospy): the recent work per task, reported
with every probe answer (:class:`~server_select.core.load.work_queue.Load`)."""

import collections
import statistics
import threading
import time

from server_select.core.util.stats import mean_error

# the standard error of a median of n draws: its variance is 1 / (4 n f(median)^2) for
# large n, sqrt(pi / 2) x sigma / sqrt(n) when the draws are normal
MEDIAN_ERROR = 1.2533


class ServiceTimes(object):
    """The recent work per task of each kind: the median of the tasks of the last
    ``horizon`` s, at least the newest ``least`` and at most ``keep``, and its standard
    error (thread-safe). A step in the work shows once half of those are new: at 4 tasks
    a second with the third slow one (0.75 s), where the last 20 had needed eleven (2.75
    s: loaded_server's reaction); fewer tasks make a wider error, which the robots count
    as noise."""

    def __init__(self, keep=20, horizon=1.0, least=3, clock=time.monotonic):
        if keep < 1 or not 1 <= least <= keep:
            raise ValueError('need 1 <= least <= keep, got %r, %r' % (least, keep))
        self.keep, self.horizon, self.least = keep, float(horizon), least
        self._clock = clock
        self._lock = threading.Lock()
        self._times = {}
        self._medians = {}
        self._errors = {}

    def add(self, kind, seconds):
        now = self._clock()
        with self._lock:
            times = self._times.get(kind)
            if times is None:
                times = self._times[kind] = collections.deque(maxlen=self.keep)
            times.append((now, float(seconds)))
            while len(times) > self.least and now - times[0][0] > self.horizon:
                times.popleft()
            values = [value for _, value in times]
            self._medians[kind] = statistics.median(values)
            self._errors[kind] = MEDIAN_ERROR * mean_error(values)[1]

    def get(self, kind, default=0.0):
        """Seconds of work per task of ``kind`` (``default`` while none was done)."""
        return self._medians.get(kind, default)

    def snapshot(self):
        """``{kind: seconds}`` of every kind done so far."""
        with self._lock:
            return dict(self._medians)

    def errors(self):
        """``{kind: the standard error of its median}`` (0.0 from one task)."""
        with self._lock:
            return dict(self._errors)
