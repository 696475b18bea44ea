"""Selection policies: which ranked server a robot gets, given the one it has (no rospy).

The same :class:`Policy` runs in the manager (per robot) and in a robot deciding alone.
It takes a :class:`~server_select.core.ranking.rank.Ranking` (servers best first by the
window's statistic) and the current choice, and returns the server to select:

- ``mean``: the best-ranked server (the paper's rule with the ``mean`` statistic); a
  ``margin`` > 0 keeps the current server while it is within it of the best (what
  ``~hysteresis`` always did).
- ``hysteresis``: keep the current server unless the best beats it by more than
  ``margin`` + ``z`` x the standard error of the difference of their statistics (a margin
  that grows with the noise; the errors are robust ones, from the median absolute
  deviation, so a step in the current server's latency does not widen it), and never move
  within ``dwell`` s of the last move unless the current server has left the ranking.

A server that leaves the ranking (no good sample in the window) is always left at once.

Rules a robot applies per task itself are policies too (:data:`PER_TASK`): the fleet
profile's ``least_latency`` (:mod:`server_select.core.rule.least_latency`) and the
league's peers (:data:`~server_select.core.peers.balancers.PEERS`: ``p2c_peak_ewma``,
``least_request``, ``prequal``, ``round_robin``, ``replicate``). The robot's ranking then
names where its tasks go, and its manager's flag says so (:meth:`Policy.choose`).
"""

import math

from server_select.core.config.names import PER_TASK_RULES
from server_select.core.ranking.rank import NO_SERVER

POLICIES = ('mean', 'hysteresis') + PER_TASK_RULES
# policies a robot applies per task itself (a balancer): the fleet's rule and the peers
PER_TASK = PER_TASK_RULES


class Policy(object):
    """One policy's rule and parameters (stateless: the caller keeps the current choice
    and when it was made)."""

    def __init__(self, kind='mean', margin=0.0, dwell=0.0, z=0.0):
        if kind not in POLICIES:
            raise ValueError('unknown policy %r (expected one of %s)'
                             % (kind, ', '.join(POLICIES)))
        for name, value in (('margin', margin), ('dwell', dwell), ('z', z)):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError('%s must be a finite number >= 0, got %r' % (name, value))
        self.kind, self.margin, self.dwell, self.z = kind, margin, dwell, z

    def statistic(self, requested='mean'):
        """The window statistic this policy ranks by: ``requested``."""
        return requested

    @property
    def per_task(self):
        """Whether robots choose per task with a peer's rule (a balancer)."""
        return self.kind in PER_TASK

    @property
    def robust(self):
        """Whether the policy needs the windows' robust standard errors."""
        return self.kind == 'hysteresis' and self.z > 0

    def choose(self, ranking, current, since=None, now=None):
        """The server to select; ``current`` was selected at ``since`` (same clock as
        ``now``; None: unknown, no dwell applies)."""
        best = ranking.selected
        if self.per_task:      # the robot chose; its ranking says what (its flag follows)
            return best
        if current is None or current == NO_SERVER or current not in ranking.ranking:
            return best
        here = ranking.means[ranking.ranking.index(current)]
        if self.kind == 'hysteresis':
            if since is not None and now is not None and now - since < self.dwell:
                return current
            return current if here - ranking.means[0] <= self._margin(ranking, current) \
                else best
        return current if self.margin > 0 and here - ranking.means[0] <= self.margin else best

    def explain(self, ranking, current, selected):
        """Why :meth:`choose` picked ``selected`` with ``current`` selected before, in the
        words the robot's log, the flag, ``top`` and ``analyze`` show."""
        if self.per_task and ranking.reason:
            return ranking.reason
        if selected == NO_SERVER or selected not in ranking.ranking:
            return 'no server answered in the window'
        best = ranking.ranking[0]
        if selected != best:
            return 'kept: within the margin of server %d' % best
        if current in ranking.ranking and current != selected:
            return 'server %d faster than %d by %.3g ms' % (
                selected, current, 1e3 * (ranking.means[ranking.ranking.index(current)] -
                                          ranking.means[0]))
        if current not in (None, NO_SERVER, selected):
            return 'the fastest (server %d left the ranking)' % current
        return 'the fastest'

    def _margin(self, ranking, current):
        errors = ranking.errors
        if not self.z or errors is None:
            return self.margin
        here, first = errors[ranking.ranking.index(current)], errors[0]
        return self.margin + self.z * math.sqrt(here * here + first * first)

    def describe(self):
        if self.kind == 'hysteresis':
            text = 'hysteresis (margin %.3g ms + %g se, dwell %.3g s)' % (
                self.margin * 1e3, self.z, self.dwell)
        else:
            text = self.kind + (' (margin %.3g ms)' % (self.margin * 1e3) if self.margin else '')
        return text


class Chooser(object):
    """A :class:`Policy` with the current choice of one robot and when it was made."""

    def __init__(self, policy):
        self.policy, self.current, self.since = policy, None, None
        self.reason = ''        # why the current choice (Policy.explain)

    def choose(self, ranking, now, current=None):
        """The server to select now (``current``: what was last published, if the caller
        knows better than this chooser, e.g. after a restart)."""
        if current is not None and current != self.current:
            self.current, self.since = current, None
        selected = self.policy.choose(ranking, self.current, self.since, now)
        if selected != self.current or self.policy.per_task or not self.reason:
            self.reason = self.policy.explain(ranking, self.current, selected)
        if selected != self.current:
            self.current, self.since = selected, now
        return selected


def from_params(get):
    """The :class:`Policy` and the window statistic that parameters ask for (``get(name)``
    reads one: ``policy``, ``statistic``, ``hysteresis``, ``dwell``, ``margin_z``)."""
    policy = Policy(get('policy'), get('hysteresis'), get('dwell'), get('margin_z'))
    return policy, policy.statistic(get('statistic'))
