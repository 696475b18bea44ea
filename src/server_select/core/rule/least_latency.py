"""The fleet profile's rule, ``least_latency`` (no rospy): the server a task is expected to
be answered soonest by, kept while nothing beats it beyond the noise.

A server's estimate, from its probe answers of the last ``window`` s: the median round
trip + the other robots' work in flight per worker (+ the robot's own tasks of its other
kinds there, :meth:`_own_kinds`) + the work per task, times the tries a server asked for
more than it can do needs; its noise the errors of these, or, when larger, how far its
level strays between windows (:meth:`wander`). ``choose`` keeps the robot's server while
it is within 3 errors of the best and not behind it for 4 windows (:meth:`_behind`); else
moves to the best or at random to one within 3 errors of it, lower than its server, not
behind the best; a frame first where it would not come back stale (:meth:`_late`).
``choose`` changes nothing: the move is made at a task's first send (:meth:`started`).
docs/selection.md has each mechanism and its worth.
"""

import collections
import math
import statistics

from server_select.core.rule.balancer import Balancer, Decision, Order
from server_select.core.ranking.rank import by_estimate
from server_select.core.util.stats import mean_error, median_error, since_step, spread_of

Z = 3.0                  # standard errors a challenger must win by
KEEP = 64                # answers kept per server at most
LEVELS = 10              # a server's levels kept, one a window: 8 second differences
# what each can be switched off for (the league's ablation: docs/selection.md)
MECHANISMS = ('keep', 'robust', 'tries', 'work_error', 'wander', 'steps', 'fresh', 'own_kinds',
              'behind')
BEHIND = 4               # levels of a kept server all above the best's: no noise (1 in 70)

Estimate = collections.namedtuple('Estimate', 'latency error wait answers')


def within(estimate, best):
    """Whether ``estimate`` is within the noise of ``best``: 3 errors of their difference."""
    return estimate.latency - best.latency <= Z * math.hypot(estimate.error, best.error)


class LeastLatency(Balancer):
    """The ``least_latency`` rule (the module docstring says what it does)."""
    name = 'least_latency'
    own_view = True
    memos = ('_wanders', '_parts')    # what its answers give anyway, kept to answer faster

    def __init__(self, window=1.5, off=(), **kwargs):
        Balancer.__init__(self, **kwargs)
        if set(off) - set(MECHANISMS):
            raise ValueError('unknown mechanisms %s (expected %s)'
                             % (sorted(set(off) - set(MECHANISMS)), ', '.join(MECHANISMS)))
        self.window, self.mechanisms = float(window), set(MECHANISMS) - set(off)
        self.answers = collections.defaultdict(lambda: collections.deque(maxlen=KEEP))
        self.least_work = {}                   # kind -> the least work any server reported
        # server -> its levels, a window apart: (when, its median round trip, {kind: work})
        self.levels = collections.defaultdict(lambda: collections.deque(maxlen=LEVELS))
        self._wanders = {}     # server -> {kind: its wander}, until its next level
        self._parts = {}       # (server, kind) -> (newest answer, count, least work, parts)

    def _probed(self, answer):
        others = max(0, answer.rif - self.attempts_out[answer.server])
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
            levels = self._levels(server, kind)
            known[kind] = spread_of(since_step(levels, Z) if 'steps' in self.mechanisms else levels)
        return known[kind]

    def _levels(self, server, kind):
        """``server``'s levels for ``kind``: each window's median round trip + work."""
        return [rtt + service.get(kind, 0.0) for _, rtt, service in self.levels.get(server, ())]

    def _draws(self):
        return self.rng.random()     # the next decision's random number

    def rate(self, kind, now):
        """The robot's ``kind`` tasks a second (the next one included: never 0), counted
        when sent (:attr:`sends`): asking where one would go is not sending it."""
        return (self.sends.count(kind, now) + 1) / self.sends.horizon

    def task_rate(self):
        now = self._clock()
        return sum(self.sends.count(kind, now) for kind in self.sends.kinds()) / self.sends.horizon

    def estimate(self, server, kind, now, rate=None):
        """The :class:`Estimate` of a ``kind`` task at ``server`` from its answers of the
        window (None: none); ``rate``: the robot's ``kind`` tasks a second (:meth:`rate`).
        Its rate-free parts once per window of answers; one try where none is over capacity."""
        kept = self.answers.get(server, ())     # (in the order heard: the window is a suffix)
        count = sum(1 for a, _ in kept if now - a.at <= self.window)
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
        return Estimate((rtt + wait + work) * tries, error * tries, wait, parts[1])

    def _own_kinds(self, server, kind, now, newest):
        """Worker-seconds a ``kind`` task at ``server`` waits for the robot's own tasks of other
        kinds there (no answer counts them): each in service rate x work of the time, half done."""
        others = sorted(k for k, there in self.chosen_for.items() if k != kind and there == server)
        wait = 0.0
        for other in others if 'own_kinds' in self.mechanisms else ():
            work = self._work(newest, other)
            wait += self.sends.count(other, now) / self.sends.horizon * work * work / 2.0
        return wait

    def _work(self, answer, kind):
        """A ``kind`` task's work (s) by ``answer``, else the least any server reported."""
        return answer.service.get(kind, self.least_work.get(kind, 0.0))

    def _rate_free(self, server, kind, answers):
        """``(round trip, wait, work, workers, error, utilizations, most)`` of ``answers``."""
        newest = answers[-1][0]
        # the newest report (a step shows at once); a kind not done there yet: what it takes
        # where nothing slows it (one task there tells). The error: the server's, of a median
        work = self._work(newest, kind)
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

    def choose(self, servers, kind=None):
        """The :class:`Decision` for the next ``kind`` task among ``servers`` (changes nothing)."""
        with self._lock:
            return self._decide(list(servers), kind, self._clock())

    def _order(self, servers, kind, now):
        decision = self._decide(servers, kind, now)
        known = decision.estimates
        return Order([decision.server] + sorted(
            (s for s in servers if s != decision.server),
            key=lambda s: (known.get(s) is None, known[s].latency if known.get(s) else 0.0)),
            {decision.server: decision.reason})

    def _decide(self, servers, kind, now):
        chosen = self.chosen_for.get(kind)
        here = chosen if chosen in servers else None
        gone = chosen is not None and here is None
        rate = self.rate(kind, now)
        estimates = self._pooled(dict((s, self.estimate(s, kind, now, rate)) for s in servers))
        known = dict((s, e) for s, e in estimates.items() if e is not None)
        if not known:
            pick = here if here is not None else servers[int(self.next_draw * len(servers))]
            return Decision(pick, 'no answer yet: at random' if here is None else
                            'no answer yet: kept', estimates)
        best = min(known, key=lambda s: known[s].latency)
        near = sorted(s for s in known if within(known[s], known[best])) \
            if 'keep' in self.mechanisms else [best]
        if here in known and (here == best or 'keep' in self.mechanisms and here in near
                              and not self._behind(here, best, kind)):
            return Decision(here, 'kept: within the noise of server %s' % best
                            if here != best else 'kept: the fastest', estimates)
        if here in known:    # a move's margin is positive, and to none behind the best
            near = [s for s in near if s == best or known[s].latency < known[here].latency
                    and not self._behind(s, best, kind)]
        there = near[int(self.next_draw * len(near))]
        why = 'server %s faster than %s by %.3g ms' % (
            there, here, 1e3 * (known[here].latency - known[there].latency)) \
            if here in known else 'server %s not usable' % chosen if gone else \
            'server %s not heard from in %g s' % (here, self.window) if here else 'the fastest'
        return Decision(there, why + (' (%d within the noise: one at random)' % len(near)
                                      if len(near) > 1 else ''), estimates)

    def _behind(self, here, best, kind):
        """Whether ``here``'s last :data:`BEHIND` levels all lie above ``best``'s (alike: 1/70)."""
        mine, theirs = (self._levels(s, kind)[-BEHIND:] for s in (here, best))
        return 'behind' in self.mechanisms and len(mine) == len(theirs) == BEHIND and \
            min(mine) > max(theirs)

    def _late(self, servers, kind, now, fresh):
        """The servers whose estimate for a ``kind`` task is past what ``fresh`` gives it
        there: a frame sent where it would come back stale is refused busy, or wasted."""
        if 'fresh' not in self.mechanisms:
            return []
        rate = self.rate(kind, now)
        known = [(s, self.estimate(s, kind, now, rate), fresh(s)) for s in servers]
        return [s for s, e, limit in known if e and limit is not None and e.latency > limit]

    @staticmethod
    def _pooled(estimates):
        """``estimates``, those of one answer given the median spread of one at the others."""
        spreads = sorted(e.error * math.sqrt(e.answers) for e in estimates.values()
                         if e is not None and e.answers > 1)
        if not spreads:
            return estimates
        spread = statistics.median(spreads)
        return dict((s, e._replace(error=max(e.error, spread)) if e and e.answers == 1 else e)
                    for s, e in estimates.items())

    def _estimates(self, servers, now):
        """``{server: Estimate or None}`` for the kind the robot sent most of lately."""
        kind = self._main_kind(now)
        rate = self.rate(kind, now)
        return self._pooled(dict((s, self.estimate(s, kind, now, rate)) for s in servers))

    def contenders(self, servers):
        """The servers worth probing often, by the choice's estimates: where each kind's tasks
        go, those within the noise of the best, and those with no answer in the window."""
        with self._lock:
            estimates = self._estimates(servers, self._clock())
            chosen = set(self.chosen_for.values())
        known = dict((s, e) for s, e in estimates.items() if e is not None)
        best = min(known.values(), key=lambda e: e.latency) if known else None
        return set(s for s in servers if s in chosen or s not in known or
                   within(known[s], best))

    def view(self, servers):
        """The servers ranked by the choice's estimates (for the manager and views): where
        tasks go first, or, that server no longer usable, where the next will go and why."""
        with self._lock:
            now = self._clock()
            if servers and self.chosen not in servers:    # (its estimates are the view's)
                decision = self._decide(list(servers), self._main_kind(now), now)
                return by_estimate(decision.estimates, decision.server, decision.reason)
            return by_estimate(self._estimates(servers, now), self.chosen, self.reason)
