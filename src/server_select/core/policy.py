"""Selection policies: which ranked server a robot gets, given the one it has (no rospy).

The same :class:`Policy` runs in the manager (per robot) and in a robot deciding alone.
It takes a :class:`~server_select.core.ranking.Ranking` (servers best first by the
window's statistic) and the current choice, and returns the server to select:

- ``mean``: the best-ranked server (the paper's rule with the ``mean`` statistic); a
  ``margin`` > 0 keeps the current server while it is within it of the best (what
  ``~hysteresis`` always did).
- ``hysteresis``: keep the current server unless the best beats it by more than
  ``margin`` + ``z`` x the standard error of the difference of their statistics (a margin
  that grows with the noise; the errors are robust ones, from the median absolute
  deviation, so a step in the current server's latency does not widen it), and never move
  within ``dwell`` s of the last move unless the current server has left the ranking.
- ``bound`` (FogROS2-LS): keep the current server while its statistic is at most
  ``bound`` s; else move to the best.
- ``peak_ewma`` (Finagle / Linkerd): the best by a peak-sensitive moving average (the
  window's ``peak_ewma`` statistic): a spike or a slowdown shows at the next sample.

A server that leaves the ranking (no good sample in the window) is always left at once.

The league's peers (:data:`~server_select.core.balancers.PEERS`: ``p2c_peak_ewma``,
``least_request``, ``prequal``, ``round_robin``, ``replicate``) are policies too: a robot
with one of them chooses per task with that rule (:mod:`server_select.core.balancers`);
its manager ranks by the mean, as with ``mean``, for the record only.

``spread`` (load-aware fleets): robots that see the same servers decide alike, and a
server that looks best draws all of them at once, gets loaded, and is left by all of them
at once (a herd). With ``spread``, a move the policy warrants away from a server that is
still ranked is taken with probability ``(1 - best / current) / 2`` (the statistics of the
two), drawn at most once per ``dwell`` s per robot (at least 1 s). Each robot that moves
both relieves its old server and loads the new one, so that half the relative gap is about
the share of robots whose moving evens two servers out: of the robots on a server that
takes twice as long as the best, a quarter move per draw (selfish load balancing,
Berenbrink et al. 2007, where a random choice of target does the halving). A move whose
gain in round trip alone (the statistics less the servers' *waits*, from load-aware
samples: backlog and work) is larger than the best server's wait is taken at once: robots
that follow it add to the wait, not to the distance, so a server that is nearer on the
network by more than the work it is asked for is not held back (the waits are those of the
ranking's statistics, the window's: the newest sample's wait set against a window's
statistic took a fall in a server's load for a gain in distance, and moved every robot on
it at once). :class:`Chooser` keeps the draws.

A draw is right for the loads it sees, and a move shows in them only once the robot's
probes announce it and the window holds samples taken since: robots that draw in that
time draw on the same old loads and move together (seen in the manager: four of five
robots left a loaded server for one idle-looking one within 0.7 s, and three came back).
The choosers of one manager share a :class:`Settling`: a server that a robot was just
moved to takes no other robot by a draw until ``seconds`` later (the manager's window),
and a robot with no server yet takes, of the servers the policy would keep if it were on
them, the best that is not settling (robots that start together go round them: a fleet's
first flags, before any load shows, put all robots on the one server the network noise
favoured). Moves that are not drawn for (its server left the ranking, nearer by more than
the wait) are not held.
"""

import math
import random
import threading

from server_select.core.balancers import PEERS
from server_select.core.ranking import NO_SERVER

POLICIES = ('mean', 'hysteresis', 'bound', 'peak_ewma', 'hot_cold') + PEERS
# policies a robot applies per task itself (a balancer): the fleet's rule and the peers
PER_TASK = ('hot_cold',) + PEERS


class Policy(object):
    """One policy's rule and parameters (stateless: the caller keeps the current choice
    and when it was made)."""

    def __init__(self, kind='mean', margin=0.0, dwell=0.0, z=0.0, bound=0.05, spread=False):
        if kind not in POLICIES:
            raise ValueError('unknown policy %r (expected one of %s)'
                             % (kind, ', '.join(POLICIES)))
        for name, value in (('margin', margin), ('dwell', dwell), ('z', z), ('bound', bound)):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError('%s must be a finite number >= 0, got %r' % (name, value))
        self.kind, self.margin, self.dwell, self.z, self.bound = kind, margin, dwell, z, bound
        self.spread = bool(spread)

    def statistic(self, requested='mean'):
        """The window statistic this policy ranks by (``requested`` unless peak_ewma)."""
        return 'peak_ewma' if self.kind == 'peak_ewma' else requested

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
        if self.kind == 'bound':
            return current if here <= self.bound else best
        if self.kind == 'hysteresis':
            if since is not None and now is not None and now - since < self.dwell:
                return current
            return current if here - ranking.means[0] <= self._margin(ranking, current) \
                else best
        return current if self.margin > 0 and here - ranking.means[0] <= self.margin else best

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
        elif self.kind == 'bound':
            text = 'bound (keep while under %.3g ms)' % (self.bound * 1e3)
        else:
            text = self.kind + (' (margin %.3g ms)' % (self.margin * 1e3) if self.margin else '')
        return text + (', spread' if self.spread else '')


class Settling(object):
    """When each server last had a robot moved to it, shared by the :class:`Chooser` s of
    one manager (thread-safe): a server is *settling* for ``seconds`` after."""

    def __init__(self, seconds):
        self.seconds = float(seconds)
        self._lock = threading.Lock()
        self._moved = {}

    def moved(self, server, now):
        with self._lock:
            self._moved[server] = now

    def settling(self, server, now):
        with self._lock:
            last = self._moved.get(server)
        return last is not None and now - last < self.seconds

    def first(self, servers, now):
        """The first of ``servers`` that is not settling, else the one whose last newcomer
        came longest ago (robots that start together go round the servers)."""
        with self._lock:
            last = [self._moved.get(s) for s in servers]
        for server, moved in zip(servers, last):
            if moved is None or now - moved >= self.seconds:
                return server
        return min(zip(last, servers))[1]


class Chooser(object):
    """A :class:`Policy` with the current choice of one robot, when it was made, and (with
    ``spread``) when the last draw was, the random numbers drawn (``rng``) and the
    :class:`Settling` it shares with the other robots' choosers (None: none)."""

    def __init__(self, policy, rng=None, settling=None):
        self.policy, self.current, self.since = policy, None, None
        self.drawn = None
        self.rng = rng or random.Random()
        self.settling = settling if policy.spread else None

    def choose(self, ranking, now, current=None):
        """The server to select now (``current``: what was last published, if the caller
        knows better than this chooser, e.g. after a restart)."""
        if current is not None and current != self.current:
            self.current, self.since = current, None
        selected = self.policy.choose(ranking, self.current, self.since, now)
        if self.settling is not None and self.current in (None, NO_SERVER) and ranking.ranking:
            # no server yet: among those the policy would keep, one not settling
            kept = [s for s in ranking.ranking if self.policy.choose(ranking, s) == s]
            selected = self.settling.first(kept or [selected], now)
        if selected != self.current and self.policy.spread and not self._draw(ranking, now):
            selected = self.current
        if selected != self.current:
            self.current, self.since = selected, now
            if self.settling is not None and selected != NO_SERVER:
                self.settling.moved(selected, now)
        return selected

    def _draw(self, ranking, now):
        """Whether a warranted move away from a still-ranked server is taken now."""
        if self.current is None or self.current not in ranking.ranking:
            return True                     # nothing to keep: no draw
        index = ranking.ranking.index(self.current)
        here, best = ranking.means[index], ranking.ranking[0]
        if _nearer(ranking, index):
            return True     # nearer by more than its wait: robots that follow cannot undo it
        if self.drawn is not None and now - self.drawn < max(1.0, self.policy.dwell):
            return False
        if self.settling is not None and self.settling.settling(best, now):
            return False        # its last newcomer does not show yet: no draw spent
        self.drawn = now
        return here > 0 and self.rng.random() < (1.0 - ranking.means[0] / here) / 2.0


def _nearer(ranking, index):
    """Whether the best server is nearer on the network than the one at ``index`` by more
    than the best's wait (the statistics' network parts and waits: a window's, not the
    newest sample's; False when the waits are not known)."""
    waits = ranking.waits
    if not waits or waits[index] is None or waits[0] is None:
        return False
    network = (ranking.means[index] - waits[index]) - (ranking.means[0] - waits[0])
    return network > waits[0]


def from_params(get):
    """The :class:`Policy` and the window statistic that parameters ask for (``get(name)``
    reads one: ``policy``, ``statistic``, ``hysteresis``, ``dwell``, ``margin_z``,
    ``latency_bound``, ``spread``)."""
    policy = Policy(get('policy'), get('hysteresis'), get('dwell'), get('margin_z'),
                    get('latency_bound'), get('spread'))
    return policy, policy.statistic(get('statistic'))
