"""What the robots send a server: the task rates they announce and, for robots that
announce nothing, the rates their tasks arrive at (no rospy); a robot's own count of what
it sends is :class:`~server_select.core.rule.estimates.SendRate`.

A load-aware robot's probe says the rate at which it sends tasks of each kind to that
server now (0 to every server but the one its next task goes to). :class:`Demand` keeps
the newest announcement of each robot for ``announce_age`` s (a robot that stopped probing
announces nothing any more) and running sums per kind, so that a probe answer costs a
subtraction however many robots probe the server; a robot that has never announced counts
by its arrivals (:class:`Arrivals`).
"""

import collections
import heapq

ROUNDING = 1e-9     # tasks a second: what subtracting announced rates may leave of none


class Arrivals(object):
    """The rate at which each sender's tasks of each kind arrive (not thread-safe: the
    :class:`WorkQueue` holds its lock).

    A sender's rate is the mean gap between its arrivals within the last ``horizon`` s
    (at most ``keep`` of them); one arrival alone counts as one per ``horizon``. A sender
    whose last arrival is older than twice its mean gap has stopped sending here (it moved
    or stopped) and counts as none, so a robot that leaves a server stops loading it within
    two of its periods rather than one horizon.
    """

    def __init__(self, horizon=10.0, keep=8):
        if not horizon > 0 or keep < 2:
            raise ValueError('horizon must be > 0 and keep >= 2, got %r, %r' % (horizon, keep))
        self.horizon, self.keep = float(horizon), int(keep)
        self._times = {}        # (owner, kind) -> deque of arrival times

    def add(self, owner, kind, now):
        times = self._times.get((owner, kind))
        if times is None:
            times = self._times[(owner, kind)] = collections.deque(maxlen=self.keep)
        times.append(now)

    def rates(self, now, excluding=None):
        """``{(owner, kind): tasks per second}`` of the senders still sending, but
        ``excluding`` (an owner)."""
        rates = {}
        for key, times in list(self._times.items()):
            while times and now - times[0] > self.horizon:
                times.popleft()
            if not times:
                del self._times[key]
                continue
            if excluding is not None and key[0] == excluding:
                continue
            gap = (times[-1] - times[0]) / (len(times) - 1) if len(times) > 1 else 0.0
            if gap <= 0:
                rates[key] = len(times) / self.horizon      # one arrival (or one instant)
            elif now - times[-1] <= 2.0 * gap:
                rates[key] = 1.0 / gap
        return rates


class Demand(object):
    """Tasks per second of each kind that robots send a server (not thread-safe: the
    :class:`~server_select.core.load.work_queue.WorkQueue` holds its lock)."""

    def __init__(self, horizon=10.0, announce_age=3.0):
        if not announce_age > 0:
            raise ValueError('announce_age must be > 0, got %r' % (announce_age,))
        self.announce_age = float(announce_age)
        self.arrivals = Arrivals(horizon)
        self._announced = {}            # owner -> (time, {kind: tasks per second})
        self._sums = collections.Counter()   # kind -> the announced rates' sum
        self._expiry = []               # heap of (time, owner) of announcements

    def arrived(self, owner, kind, now):
        """A task of ``owner`` (None: of nobody) came in at ``now``."""
        if owner not in self._announced:
            self.arrivals.add(owner, kind, now)

    def announce(self, owner, rates, now):
        """``owner`` sends ``(kind, tasks per second)`` pairs here from ``now`` on."""
        self._expire(now)
        self._drop(owner)
        rates = dict((kind, float(rate)) for kind, rate in rates if rate > 0)
        self._announced[owner] = (now, rates)
        self._sums.update(rates)
        heapq.heappush(self._expiry, (now, owner))

    def rates(self, now, excluding=None):
        """``{kind: tasks per second}`` of every robot but ``excluding``."""
        self._expire(now)
        rates = dict((kind, rate) for kind, rate in self._sums.items() if rate > 0)
        own = self._announced.get(excluding) if excluding is not None else None
        for kind, rate in (own[1] if own else {}).items():
            rates[kind] = max(0.0, rates.get(kind, 0.0) - rate)
        for (owner, kind), rate in self.arrivals.rates(now, excluding).items():
            if owner not in self._announced:
                rates[kind] = rates.get(kind, 0.0) + rate
        return rates

    def others(self, now, owner):
        """Whether a robot other than ``owner`` (None too) sends here now (it announces a
        rate, or its tasks still arrive)."""
        self._expire(now)
        return any(other != owner and rates for other, (_, rates) in self._announced.items()) \
            or any(other != owner and other not in self._announced
                   for other, _ in self.arrivals.rates(now))

    def _drop(self, owner):
        entry = self._announced.pop(owner, None)
        if entry is not None:
            self._sums.subtract(entry[1])
            for kind in entry[1]:      # no rounding left over: a rate nobody announces is none
                if self._sums[kind] < ROUNDING:
                    del self._sums[kind]

    def _expire(self, now):
        while self._expiry and now - self._expiry[0][0] > self.announce_age:
            when, owner = heapq.heappop(self._expiry)
            entry = self._announced.get(owner)
            if entry is not None and entry[0] == when:
                self._drop(owner)
        if not self._announced:
            self._sums.clear()          # no rounding left over
