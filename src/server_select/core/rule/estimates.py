"""What a robot expects of each of its servers (no rospy): one load model, read by the
fleet's rule to choose and by every robot's attempt deadlines, hedges and fresh frames.

A server's estimate for a ``kind`` task, from its probe answers of the last ``window`` s:
the median round trip + the other robots' work in flight per worker (+ the robot's own
tasks of its other kinds there, :meth:`ServerEstimates._own_kinds`) + the work per task,
times the tries a server asked for more than it can do needs. Its noise: the errors of
these or, when larger, how far its level strays between windows (:meth:`wander`). A kind
a server has not done yet needs the least work any server reported for it (one task there
tells). ``mechanisms`` names the parts in use (the league's ablation switches them off).
The robot's own tasks count by :class:`SendRate`, its one count of what it sends.
"""

import collections
import math
import statistics
import threading
import time

from server_select.core.util.stats import mean_error, median_error, since_step, spread_of

Z = 3.0                  # standard errors a challenger must win by (a level's step too)
KEEP = 64                # answers kept per server at most
LEVELS = 10              # a server's levels kept, one a window: 8 second differences
RATE_HORIZON = 5.0       # s of a robot's own attempts its send rate is counted over
MECHANISMS = ('robust', 'tries', 'work_error', 'wander', 'steps', 'own_kinds')

Estimate = collections.namedtuple('Estimate', 'latency error wait answers rtt work')
Estimate.__doc__ = """A ``kind`` task at a server: ``latency`` (s, what the rule ranks by),
its ``error``, the ``wait`` for a worker, the ``answers`` it rests on, their median round
trip ``rtt`` and the ``work`` per task (s)."""


class SendRate(object):
    """A robot's own attempts of each kind in the last :data:`RATE_HORIZON` s: the one
    count of what it sends, read by its rule (its tasks' share of a server) and by its
    probes (the rate they announce). Told of each attempt as the robot's other attempt
    observers are (``started``, ``ended``). Thread-safe."""

    def __init__(self, clock=time.monotonic, horizon=RATE_HORIZON):
        self.horizon, self._clock = float(horizon), clock
        self._lock = threading.Lock()
        self._times = {}          # kind -> deque of when its attempts were sent

    def started(self, server, kind=None, first=True, order=None):
        now = self._clock()
        with self._lock:
            times = self._times.get(kind)
            if times is None:
                times = self._times[kind] = collections.deque()
            times.append(now)
            while now - times[0] > self.horizon:
                times.popleft()

    def ended(self, server, rtt=None):
        """(An attempt's end changes no rate.)"""

    def count(self, kind, now):
        """``kind`` attempts sent in the last :attr:`horizon` s before ``now``."""
        with self._lock:
            return sum(1 for t in self._times.get(kind, ()) if now - t <= self.horizon)

    def kinds(self):
        """Every kind sent so far (None: attempts told no kind)."""
        with self._lock:
            return list(self._times)


class ServerEstimates(object):
    """The estimates of a robot's servers (see the module's docstring). ``sends``: the
    robot's :class:`SendRate`; ``chosen_for``: ``{kind:
    server}`` where each kind's tasks go (the rule's, read, never written here). Not
    thread-safe: its rule's lock covers it."""
    memos = ('_wanders', '_parts')    # what its answers give anyway, kept to answer faster

    def __init__(self, window, sends, chosen_for, mechanisms=MECHANISMS):
        self.window, self.sends, self.chosen_for = float(window), sends, chosen_for
        self.mechanisms = set(mechanisms)
        self.answers = collections.defaultdict(lambda: collections.deque(maxlen=KEEP))
        self.least_work = {}                   # kind -> the least work any server reported
        # server -> its levels, a window apart: (when, its median round trip, {kind: work})
        self.levels = collections.defaultdict(lambda: collections.deque(maxlen=LEVELS))
        self._wanders = {}     # server -> {kind: its wander}, until its next level
        self._parts = {}       # (server, kind) -> (newest answer, count, least work, parts)

    def heard(self, answer, others):
        """A probe answer (a ``ProbeAnswer``) with ``others`` of the other robots' tasks
        in flight there."""
        answers = self.answers[answer.server]
        answers.append((answer, others))     # (in the order heard: a window is a suffix)
        while answer.at - answers[0][0].at > self.window:   # out of every later window
            answers.popleft()
        for kind, work in answer.service.items():
            self.least_work[kind] = min(work, self.least_work.get(kind, work))
        levels = self.levels[answer.server]
        if not levels or answer.at - levels[-1][0] >= self.window:
            rtt = statistics.median(a.rtt for a, _ in answers)
            levels.append((answer.at, rtt, answer.service))
            self._wanders.pop(answer.server, None)

    def wander(self, server, kind):
        """How far ``server``'s level for ``kind`` (its window's median round trip + work)
        strays, as a standard deviation: the median of its last second differences over
        0.6745 x sqrt 6. A trend (a robot moving, links crossing) has none, and one step
        (a slowed server) makes two of eight, which the median passes over; a load that came
        and went makes many: only the levels since count (``since_step``); 0.0 before four."""
        if 'wander' not in self.mechanisms:
            return 0.0
        known = self._wanders.setdefault(server, {})    # (asked per estimate: kept)
        if kind not in known:
            levels = self.level_series(server, kind)
            known[kind] = spread_of(since_step(levels, Z) if 'steps' in self.mechanisms else levels)
        return known[kind]

    def level_series(self, server, kind, reported=False):
        """``server``'s levels for ``kind``: each window's median round trip + work (0.0
        where it reported none; ``reported``: only the windows where it reported some)."""
        return [rtt + service.get(kind, 0.0) for _, rtt, service in self.levels.get(server, ())
                if not reported or kind in service]

    def rate(self, kind, now):
        """The robot's ``kind`` tasks a second (the next one included: never 0), counted
        when sent: asking where one would go is not sending it."""
        return (self.sends.count(kind, now) + 1) / self.sends.horizon

    def estimate(self, server, kind, now, rate=None):
        """The :class:`Estimate` of a ``kind`` task at ``server`` from its answers of the
        window (None: none); ``rate``: the robot's ``kind`` tasks a second (:meth:`rate`).
        Its rate-free parts once per window of answers; one try where none is over capacity."""
        kept = self.answers.get(server, ())     # (in the order heard: the window is a suffix)
        count = len(kept)
        for answer, _ in kept:                  # (the older ones first: few, or none)
            if now - answer.at <= self.window:
                break
            count -= 1
        if not count:
            return None
        rate = self.rate(kind, now) if rate is None else rate
        newest, least = kept[-1][0], self.least_work.get(kind)
        parts = self._parts.get((server, kind))
        if parts is None or parts[0] is not newest or parts[1:3] != (count, least):
            parts = self._parts[(server, kind)] = (newest, count, least, self._rate_free(
                server, kind, list(kept)[len(kept) - count:]))
        rtt, wait, work, workers, error, utilizations, busiest = parts[3]
        wait += self._own_kinds(server, kind, now, newest) / workers
        mine = rate * work / workers
        tries = 1.0 if 'tries' not in self.mechanisms or busiest + mine <= 1.0 else \
            math.fsum([max(1.0, u + mine) for u in utilizations]) / len(utilizations)
        return Estimate((rtt + wait + work) * tries, error * tries, wait, parts[1], rtt, work)

    def answer_wait(self, server, kind):
        """Seconds a ``kind`` task waits and works at ``server`` by its newest answer alone
        (the others' work in flight per worker + the work; None: no answer): one sample's
        part of the estimate, which a ranking of samples averages over its window."""
        kept = self.answers.get(server)
        if not kept:
            return None
        answer, others = kept[-1]
        work = self.work(answer, kind)
        return others * work / answer.workers + work

    def _own_kinds(self, server, kind, now, newest):
        """Worker-seconds a ``kind`` task at ``server`` waits for the robot's own tasks of other
        kinds there (no answer counts them): each in service rate x work of the time, half done."""
        others = sorted(k for k, there in self.chosen_for.items() if k != kind and there == server)
        wait = 0.0
        for other in others if 'own_kinds' in self.mechanisms else ():
            work = self.work(newest, other)
            wait += self.sends.count(other, now) / self.sends.horizon * work * work / 2.0
        return wait

    def work(self, answer, kind):
        """A ``kind`` task's work (s) by ``answer``, else the least any server reported."""
        return answer.service.get(kind, self.least_work.get(kind, 0.0))

    def _rate_free(self, server, kind, answers):
        """``(round trip, wait, work, workers, error, utilizations, most)`` of ``answers``."""
        newest = answers[-1][0]
        # the newest report (a step shows at once); a kind not done there yet: what it takes
        # where nothing slows it (one task there tells). The error: the server's, of a median
        work = self.work(newest, kind)
        work_error = newest.service_error.get(kind, 0.0) if 'work_error' in self.mechanisms else 0.0
        workers = float(newest.workers)
        rtts = [a.rtt for a, _ in answers]
        queued = [others * work / workers for _, others in answers]
        # robust: a late answer or two (a retransmission, a hang ending) must not hold the mean up
        rtt, rtt_error = (median_error if 'robust' in self.mechanisms else mean_error)(rtts)
        wait, wait_error = mean_error(queued)
        error = max(math.sqrt(rtt_error ** 2 + wait_error ** 2 + work_error ** 2),
                    self.wander(server, kind))
        utilizations = [a.utilization for a, _ in answers]
        return rtt, wait, work, workers, error, utilizations, max(utilizations)

    def pooled(self, estimates):
        """``estimates``, those of one answer given the median spread of one at the others."""
        spreads = sorted(e.error * math.sqrt(e.answers) for e in estimates.values()
                         if e is not None and e.answers > 1)
        if not spreads:
            return estimates
        spread = statistics.median(spreads)
        return dict((s, e._replace(error=max(e.error, spread)) if e and e.answers == 1 else e)
                    for s, e in estimates.items())
