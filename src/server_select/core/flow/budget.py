"""How many extra sends (re-sends, hedges) a robot may make: a budget (no rospy).

Under overload a re-send or a hedge is one more task for servers that have no time to
spare. As Finagle's ``RetryBudget`` and gRPC's retry throttling do, extra sends are paid
from a budget: at most ``ratio`` of the tasks first sent in the last ``window`` s, plus a
``reserve`` of 2. A task stranded on a server that has stopped (more than ``reserve``
attempts sent there since it last answered anything) goes elsewhere without drawing on it:
none of those attempts is being worked on, so their re-sends add no work. A robot at 5
tasks/s with 1 s attempt deadlines has 5 out on a server that stops, and a fixed 2 failed
the last of them; when those re-sends were paid from the window, a task late once on the
next server 2 s later found it spent and failed. A hedge (a copy of a task nobody has
failed) never draws on the reserve: in a scenario with a link outage, hedges had spent
what the re-sends after it needed, and a task failed.
"""

import collections
import threading
import time


class RetryBudget(object):
    """Thread-safe; ``ratio`` 0 means no limit."""

    def __init__(self, ratio=0.1, window=10.0, reserve=2, clock=time.monotonic):
        if ratio < 0 or not window > 0 or reserve < 0:
            raise ValueError('need ratio >= 0, window > 0, reserve >= 0: %r %r %r'
                             % (ratio, window, reserve))
        self.ratio, self.window, self.reserve = float(ratio), float(window), reserve
        self._clock = clock
        self._lock = threading.Lock()
        self._sent, self._spent = collections.deque(), collections.deque()
        self.refused = 0

    def _prune(self, now):
        for times in (self._sent, self._spent):
            while times and times[0] <= now - self.window:
                times.popleft()

    def sent(self):
        """A task was sent for the first time."""
        if not self.ratio:
            return
        with self._lock:
            now = self._clock()
            self._prune(now)
            self._sent.append(now)

    def spend(self, reserve=True, stranded=0):
        """Whether one extra send may go now (and it is counted when it may); ``reserve``
        False (a hedge): only within the ratio; ``stranded``: the attempts sent since it
        last answered anything to the server this task is re-sent from, which did not
        answer it in time (more than ``reserve``: the server has stopped, and the re-send
        is free; a server that answers, even late, resets the count)."""
        if not self.ratio:
            return True
        if reserve and stranded > self.reserve:
            return True
        with self._lock:
            now = self._clock()
            self._prune(now)
            allowed = self.ratio * len(self._sent) + (self.reserve if reserve else 0)
            if len(self._spent) >= allowed:
                self.refused += 1
                return False
            self._spent.append(now)
            return True

    def describe(self):
        if not self.ratio:
            return 'no limit'
        return '%g %% of tasks + %d per %g s' % (100 * self.ratio, self.reserve, self.window)
