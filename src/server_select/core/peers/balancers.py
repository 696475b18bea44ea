"""Per-task balancers: the rules a user would put in front of servers instead of ours
(no rospy). The league (``make league``) runs each beside the fleet profile.

Each chooses per task, in the robot, from the robot's own evidence, and returns every
server it may use in its order of preference (the first gets the task; a re-send or hedge
takes the next): :meth:`Balancer.order`. What the robot tells them: its probe answers
(:meth:`Balancer.probed`: round trip and the server's
:class:`~server_select.core.load.work_queue.Load`),
its attempts (:meth:`Balancer.started`, :meth:`Balancer.ended`: round trip of an answer, or
of an attempt that failed), and the kind of task it is about to send.

- ``p2c_peak_ewma`` (Finagle ``Balancers.p2cPeakEwma``, tower ``balance::p2c`` with
  ``load::PeakEwma``, Linkerd): two distinct servers drawn at random, the lower cost wins;
  cost = peak-EWMA of the attempts' round trips x (this robot's attempts out there + 1).
  As in tower and Finagle the estimate decays towards 0 between samples (so a server left
  alone is tried again), a sample above it replaces it at once, and a server with no sample
  starts at 1 s (tower's default). Decay time 10 s (tower's and Finagle's default).
- ``least_request`` (Envoy ``LEAST_REQUEST``, equal weights): two servers drawn at random,
  fewer of this robot's attempts out there wins (a tie: the first drawn).
- ``prequal`` (Wydrowski et al., NSDI '24): a pool of at most 16 probe answers, none
  older than 1 s, each used for at most ``reuse`` tasks, one answer removed per task
  (alternately the oldest and the worst); an answer is *hot* when its requests in flight
  (RIF: queued + in service) are above the 2^-0.25 quantile of the pool's; the cold answer
  with the lowest latency wins, else (all hot) the lowest RIF; fewer than 2 answers: at
  random. Adaptations, forced by robots: latency is the robot's own probe round trip plus
  the server's reported work for the task's kind (a web client's network is the same to
  every server, a robot's is not; the server reports its recent work per kind, not a
  latency at a given RIF); probes come from the robot's prober at its own rates (all
  servers, uniformly, in the league), not 3 per query (a robot sends 1-5 tasks a second
  and probes far more often, so the pool is always fresh; ``reuse`` 2 rarely binds).
- ``round_robin``: servers in turn, each as often as its workers (from its probe answers;
  1 until known): smooth weighted round robin (nginx's), the baseline Prequal measures.
- ``replicate`` (FogROS2-FT / -PLR): each task to the two best servers by this robot's
  probes' mean round trip; the first answer wins (:attr:`Balancer.copies` is 2).

Every peer meets the robot's own health (a server that failed is skipped while ejected),
as production balancers have outlier detection; nothing else of the fleet profile's
selection applies to them.
"""

import collections
import math

from server_select.core.config.names import PEERS  # noqa: F401 (re-exported)
from server_select.core.rule.balancer import Balancer
from server_select.core.rule.least_latency import LeastLatency
from server_select.core.util.stats import percentile


class PeakEwma(object):
    """A peak-sensitive moving average of round trips (Finagle's ``PeakEwma`` cost, tower's
    ``RttEstimate``): a sample above the estimate replaces it; one below moves it by
    ``1 - exp(-dt / tau)`` (``dt`` since the last sample); a read sees it decayed towards
    0 the same way. Both implementations store that decay on every read (an update with a
    0 round trip); here a read stores nothing, so that asking is not deciding."""

    def __init__(self, now, tau=10.0, initial=1.0):
        if not tau > 0:
            raise ValueError('tau must be positive, got %r' % (tau,))
        self.tau, self.estimate, self.stamp = float(tau), float(initial), now

    def observe(self, rtt, now):
        if rtt > self.estimate:
            self.estimate = rtt
        else:
            w = math.exp(-max(0.0, now - self.stamp) / self.tau)
            self.estimate = self.estimate * w + rtt * (1.0 - w)
        self.stamp = now

    def get(self, now):
        return self.estimate * math.exp(-max(0.0, now - self.stamp) / self.tau)


def _pair_first(drawn, servers, key):
    """The pair ``drawn`` by ``key`` (strictly lower wins; a tie keeps the first drawn),
    then the other servers by ``key`` (where re-sends go)."""
    pair = sorted(drawn, key=key) if len(drawn) == 2 and key(drawn[1]) < key(drawn[0]) \
        else list(drawn)
    return pair + sorted((s for s in servers if s not in pair), key=key)


class P2CPeakEwma(Balancer):
    name = 'p2c_peak_ewma'

    def __init__(self, tau=10.0, initial=1.0, **kwargs):
        Balancer.__init__(self, **kwargs)
        self.tau, self.initial = tau, initial
        self.ewma = {}

    def _met(self, server, now):
        """``server``'s estimate, kept from when the robot first meets it (its first probe
        answer or attempt), as in tower."""
        if server not in self.ewma:
            self.ewma[server] = PeakEwma(now, self.tau, self.initial)
        return self.ewma[server]

    def _probed(self, answer):
        self._met(answer.server, answer.at)

    def _started(self, server, kind, now):
        self._met(server, now)

    def _ended(self, server, rtt, now):
        self._met(server, now).observe(rtt, now)

    def cost(self, server, now):
        """Its estimate x (attempts out + 1); one not met yet at the initial estimate."""
        ewma = self.ewma.get(server)
        estimate = ewma.get(now) if ewma is not None else self.initial
        return estimate * (self.attempts_out[server] + 1)

    def _order(self, servers, kind, now):
        costs = dict((s, self.cost(s, now)) for s in servers)
        return _pair_first(self._two(servers), servers, costs.__getitem__)


class LeastRequest(Balancer):
    name = 'least_request'

    def _order(self, servers, kind, now):
        return _pair_first(self._two(servers), servers, lambda s: self.attempts_out[s])


class RoundRobin(Balancer):
    """Smooth weighted round robin: each turn every server gains its weight, the one with
    the most goes and loses the total."""
    name = 'round_robin'

    def __init__(self, **kwargs):
        Balancer.__init__(self, **kwargs)
        self.current = collections.defaultdict(float)

    def _weights(self, servers):
        return dict((s, self.probes[s].workers if s in self.probes else 1) for s in servers)

    def _order(self, servers, kind, now):
        weights = self._weights(servers)
        turn = max(servers, key=lambda s: (self.current[s] + weights[s], -servers.index(s)))
        return [turn] + [s for s in servers if s != turn]

    def _chosen(self, server, kind, now, order):
        """The turn taken: every server asked about gains its weight, the one sent to
        loses the total."""
        weights = self._weights(list(order))
        for s, weight in weights.items():
            self.current[s] += weight
        self.current[server] -= sum(weights.values())


class Replicate(Balancer):
    """The two best by the mean of the robot's probes' round trips (its last ``keep``)."""
    name = 'replicate'
    copies = 2

    def __init__(self, keep=8, **kwargs):
        Balancer.__init__(self, **kwargs)
        self.rtts = collections.defaultdict(lambda: collections.deque(maxlen=keep))

    def _probed(self, answer):
        self.rtts[answer.server].append(answer.rtt)

    def _order(self, servers, kind, now):
        def mean(s):
            rtts = self.rtts.get(s)
            return sum(rtts) / len(rtts) if rtts else float('inf')
        return sorted(servers, key=lambda s: (mean(s), servers.index(s)))


class Prequal(Balancer):
    """Prequal's probe pool and hot-cold rule (the module docstring says what is adapted)."""
    name = 'prequal'
    HOT_QUANTILE = 2 ** -0.25

    def __init__(self, pool=16, max_age=1.0, reuse=2, q=HOT_QUANTILE, **kwargs):
        Balancer.__init__(self, **kwargs)
        self.size, self.max_age, self.reuse, self.q = pool, max_age, reuse, q
        self.pool = []            # [ProbeAnswer, uses], oldest first
        self._remove_oldest = True

    def _probed(self, answer):
        self.pool.append([answer, 0])
        if len(self.pool) > self.size:
            self.pool.pop(0)

    def latency(self, answer, kind):
        return answer.rtt + answer.service.get(kind, 0.0)

    def hot(self, entries):
        """The answers of ``entries`` that are hot (RIF above the pool's quantile)."""
        limit = percentile(sorted(e[0].rif for e in entries), 100 * self.q)
        return [e for e in entries if e[0].rif > limit]

    def _ranked(self, servers, kind, now):
        """``(the pool's fresh answers, those of ``servers`` in the rule's order, their
        rank)``; None for the rank with fewer than 2 such answers."""
        usable = set(servers)
        pool = [e for e in self.pool if now - e[0].at <= self.max_age]
        entries = [e for e in pool if e[0].server in usable]
        if len(entries) < 2:
            return pool, entries, None
        hot = self.hot(entries)
        cold = [e for e in entries if not any(e is h for h in hot)]

        def rank(e):   # the rule's order: cold by latency, then hot by RIF
            return (0, self.latency(e[0], kind), e[0].rif) if any(e is c for c in cold) \
                else (1, e[0].rif, self.latency(e[0], kind))
        return pool, sorted(entries, key=rank), rank

    def _order(self, servers, kind, now):
        _, ranked, rank = self._ranked(servers, kind, now)
        if rank is None:
            first = servers[int(self.next_draw[0] * len(servers))]
            return [first] + [s for s in servers if s != first]
        order = []
        for e in ranked:
            if e[0].server not in order:
                order.append(e[0].server)
        return order + [s for s in servers if s not in order]

    def _chosen(self, server, kind, now, order):
        """The pool's bookkeeping for a query: the answer used counts a use (gone after
        ``reuse``), else one answer goes, oldest and worst in turn."""
        self.pool, ranked, rank = self._ranked(list(order), kind, now)
        chosen = next((e for e in ranked if e[0].server == server), None)
        if rank is None or chosen is None:
            return
        chosen[1] += 1
        if chosen[1] >= self.reuse:
            self.pool.remove(chosen)
        elif len(self.pool) > 1:      # one answer goes per query: oldest, worst, in turn
            self.pool.remove(self.pool[0] if self._remove_oldest else
                             max(self.pool, key=rank))
            self._remove_oldest = not self._remove_oldest


_CLASSES = dict((c.name, c) for c in (P2CPeakEwma, LeastRequest, Prequal, RoundRobin,
                                      Replicate))


def make(name, **kwargs):
    """The balancer called ``name`` (one of :data:`PEERS`, or the fleet's ``least_latency``)."""
    if name == 'least_latency':
        return LeastLatency(**kwargs)
    if name not in _CLASSES:
        raise ValueError('unknown balancer %r (expected one of %s)' % (name, ', '.join(PEERS)))
    return _CLASSES[name](**kwargs)
