"""The fleet profile's rule, ``least_latency`` (no rospy): the server a task is expected to
be answered soonest by, kept while nothing beats it beyond the noise.

A server's estimate is the robot's one load model (round trip + wait + work from the
answers of the last ``window`` s, and its noise: :mod:`~server_select.core.rule.estimates`),
which its attempt deadlines follow too. ``choose`` keeps the robot's server while it is
within 3 errors of the best and not behind it for 5 windows (:meth:`_behind`); else moves
to the best or at random to one within 3 errors of it, lower than its server, not behind
the best; a frame first where it would not come back stale (:meth:`_late`).
``choose`` changes nothing: the move is made at a task's first send (:meth:`started`).
docs/selection.md has each mechanism and its worth.
"""

import math

from server_select.core.rule.balancer import Balancer, Decision, Order
from server_select.core.rule import estimates as estimating
from server_select.core.rule.estimates import Z
from server_select.core.ranking.rank import by_estimate

# what each can be switched off for (the league's ablation: docs/selection.md)
MECHANISMS = ('keep', 'robust', 'tries', 'work_error', 'wander', 'steps', 'fresh', 'own_kinds',
              'behind')
BEHIND = 5               # levels of a kept server all above the best's: no noise (1 in 252)


def within(estimate, best):
    """Whether ``estimate`` is within the noise of ``best``: 3 errors of their difference."""
    return estimate.latency - best.latency <= Z * math.hypot(estimate.error, best.error)


class LeastLatency(Balancer):
    """The ``least_latency`` rule (the module docstring says what it does)."""
    name = 'least_latency'
    own_view = True

    def __init__(self, window=1.5, off=(), **kwargs):
        if set(off) - set(MECHANISMS):
            raise ValueError('unknown mechanisms %s (expected %s)'
                             % (sorted(set(off) - set(MECHANISMS)), ', '.join(MECHANISMS)))
        self.mechanisms = set(MECHANISMS) - set(off)
        Balancer.__init__(self, window=window, mechanisms=[
            m for m in estimating.MECHANISMS if m in self.mechanisms], **kwargs)

    def _draws(self):
        return self.rng.random()     # the next decision's random number

    def rate(self, kind, now):
        """The robot's ``kind`` tasks a second (the next one included: never 0)."""
        return self.estimates.rate(kind, now)

    def task_rate(self):
        now = self._clock()
        return sum(self.sends.count(kind, now) for kind in self.sends.kinds()) / self.sends.horizon

    def estimate(self, server, kind, now, rate=None):
        """The :class:`~server_select.core.rule.estimates.Estimate` of a ``kind`` task at
        ``server`` (None: no answer in the window)."""
        return self.estimates.estimate(server, kind, now, rate)

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
        estimates = self.estimates.pooled(
            dict((s, self.estimate(s, kind, now, rate)) for s in servers))
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
        """Whether ``here``'s last :data:`BEHIND` levels all lie above ``best``'s (alike: 1/252),
        counting a level only where its server reported work for ``kind`` (a server yet to do
        one lies behind none by the work it has not reported)."""
        levels = self.estimates.level_series
        mine, theirs = (levels(s, kind, reported=True)[-BEHIND:] for s in (here, best))
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

    def _estimates(self, servers, now):
        """``{server: Estimate or None}`` for the kind the robot sent most of lately."""
        kind = self._main_kind(now)
        rate = self.rate(kind, now)
        return self.estimates.pooled(dict((s, self.estimate(s, kind, now, rate)) for s in servers))

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
