"""When this process stood still (no rospy): stopped (SIGSTOP), frozen or its host paused.

A task timed across such a pause measured the pause, not the server's work. Reported as
its work, a 5 s stop made a server that had frames in progress say each takes seconds, so
the robots that had left it did not come back until it forgot that work, 10 s later
(:class:`~server_select.core.load.service_times.ServiceTimes`' ``idle``). Nothing inside a
process sees its own stop, so a thread of the server ticks every ``tick`` s; a gap of more
than ``least`` s between two ticks is a pause. A task that ends before the ticker has run
again after a pause sees the tick itself overdue.
"""

import collections
import threading
import time


class Pauses(object):
    """The last ``keep`` pauses longer than ``least`` s (thread-safe; :meth:`tick` from
    one thread every ``tick`` s, well under ``least``)."""

    def __init__(self, least=1.0, tick=0.2, keep=16, clock=time.monotonic):
        if not 0 < tick < least:
            raise ValueError('need 0 < tick < least, got %r, %r' % (tick, least))
        self.least, self.tick_seconds, self._clock = float(least), float(tick), clock
        self._lock = threading.Lock()
        self._last = clock()
        self._gaps = collections.deque(maxlen=keep)      # (last tick before, first after)

    def tick(self):
        """The ticker's beat: a gap since the last one longer than ``least`` was a pause
        (returned in s; 0.0 when there was none)."""
        now = self._clock()
        with self._lock:
            gap = now - self._last
            self._last = now
            if gap <= self.least:
                return 0.0
            self._gaps.append((now - gap, now))
        return gap

    def across(self, start, end):
        """Whether the span from ``start`` to ``end`` (this clock's seconds) held a
        pause, one the ticker saw or one it has not run since."""
        with self._lock:
            if end - self._last > self.least:
                return True
            return any(before < end and start < after for before, after in self._gaps)

    def run(self, stopped=lambda: False, sleep=time.sleep):
        """Tick until ``stopped()`` (a thread's whole life)."""
        while not stopped():
            self.tick()
            sleep(self.tick_seconds)
