"""The fleet profile's selection rule, ``hot_cold`` (no rospy): Prequal's lexicographic
comparison (avoid the hot, then take the fastest), made sticky for robots.

Per task, from the robot's own evidence (a :class:`~server_select.core.balancers.Balancer`:
the robot tells it its probe answers, its attempts, and the kind of task it sends):

1. The candidates are the servers the robot's health has not ejected (the caller's list).
2. A server's *latency* for a task of a kind is its *expected completion*, from each of
   its last :data:`RTTS` probe answers: the robot's round trip + the wait for a worker +
   the work per task of that kind (the median of what the servers report, where it has
   done none yet). The wait is the larger of two: the M/D/c mean wait
   (:func:`~server_select.core.load_board.queueing`) at the utilization the server would
   have with the robot's tasks on it (what it reports for the other robots' tasks plus
   the robot's own rate of this kind, over its last :data:`RATE_HORIZON` s, x the work),
   and the other robots' work in flight there (their requests queued and in service x
   the work, per worker), which is what a saturated server makes a task wait. The
   latency is the median of those, its noise their robust standard error. Every server
   is judged as if the robot were on it, its own too: a move is worth it only when the
   other server is faster *after* the robot's tasks have joined it (a best response in
   selfish load balancing).
3. A server is *hot* when the others' work in flight per worker (the median over its last
   answers, so that one answer that caught another robot's task does not make it hot) is
   above the 2^-0.25 quantile of the candidates' (Prequal's rule, on work rather than on
   requests: servers of unequal speed carry unequal numbers of requests).
4. The robot **keeps** the server its last task went to while that server is cold and no
   cold server's latency is lower by more than the noise of the comparison: 3 standard
   errors of the difference of the two latencies. Else it takes a cold server of the
   lowest latency, at random among those within that noise of it (robots that see the
   same servers do not all move to one); every candidate hot: the least work in flight;
   no answer yet from any candidate: one at random (Prequal with fewer than 2 answers),
   which also spreads robots that start together.

Adapted from Prequal (NSDI '24) for robots: latency is the robot's own round trip plus the
server's expected wait and work (a robot's network differs per server; a web client's does
not), requests in flight leave out the robot's own (a robot with one task out would see its
own server one task hotter than the rest and leave it for nothing), requests count by
their work (servers differ in speed), each server's last few answers stand for the pool
(a robot probes every server several times a second), and the choice is kept while
nothing beats it (a move is a new connection and a cold start at the server: per-request
choice suits a web client with many requests in flight, not a robot with one). No
parameter: the quantile, the 3 errors and the 5 answers are the rule's.
"""

import collections
import math
import statistics

from server_select.core.balancers import Balancer, quantile
from server_select.core.load_board import queueing

RTTS = 5                 # probe answers per server the estimates are the medians of
HOT_QUANTILE = 2 ** -0.25
Z = 3.0                  # standard errors a challenger must win by
MAX_AGE = 3.0            # s: an older probe answer does not count (the probes stopped)
RATE_HORIZON = 5.0       # s of the robot's own tasks its rate is counted over


def robust_error(values):
    """The standard error of the median of ``values`` from their median absolute
    deviation (1.4826 x MAD is the standard deviation of normal data; the median's error is
    1.253 x that over the root of the count); 0.0 for fewer than 2 values."""
    if len(values) < 2:
        return 0.0
    centre = statistics.median(values)
    mad = statistics.median(abs(v - centre) for v in values)
    return 1.253 * 1.4826 * mad / math.sqrt(len(values))


Answer = collections.namedtuple('Answer', 'rtt others utilization')


class HotCold(Balancer):
    """The ``hot_cold`` rule (the module docstring says what it does)."""
    name = 'hot_cold'

    def __init__(self, **kwargs):
        Balancer.__init__(self, **kwargs)
        # server -> its last answers: round trip, others' requests in flight, utilization
        self.answers = collections.defaultdict(lambda: collections.deque(maxlen=RTTS))
        self.current = None
        self.why = 'no task yet'
        self.sends = collections.defaultdict(collections.deque)   # kind -> its task times
        self.moves = collections.Counter()     # why the robot changed server, how often
        self.errors = {}                       # server -> its latency's standard error

    def _probed(self, answer):
        others = max(0, answer.rif - self.out[answer.server])
        self.answers[answer.server].append(Answer(answer.rtt, others, answer.utilization))

    def _work(self, answer, kind, fresh):
        if kind in answer.service:
            return answer.service[kind]
        known = [a.service[kind] for a in fresh.values() if kind in a.service]
        return statistics.median(known) if known else 0.0

    def rate(self, kind, now):
        """The robot's ``kind`` tasks per second over the last :data:`RATE_HORIZON` s."""
        times = self.sends[kind]
        while times and now - times[0] > RATE_HORIZON:
            times.popleft()
        span = now - times[0] if len(times) > 1 else 0.0
        return (len(times) - 1) / span if span > 0 else 0.0

    def estimate(self, newest, kind, fresh, rate=0.0):
        """``(latency, its standard error, work in flight per worker)`` of a ``kind`` task
        at ``newest``'s server (its newest answer) with the robot's own ``rate`` of them
        there: each of the server's last answers gives a latency, round trip + wait +
        work, the wait being the larger of the M/D/c mean at its utilization with the
        robot's tasks and the others' work in flight per worker; the median of them, its
        robust error, and the median of the work in flight."""
        work = self._work(newest, kind, fresh)
        workers = float(newest.workers)
        mine = rate * work / workers
        latencies, heat = [], []
        for a in self.answers[newest.server] or [Answer(newest.rtt, 0, newest.utilization)]:
            queued = a.others * work / workers
            latencies.append(a.rtt + max(queueing(a.utilization + mine, work, workers),
                                         queued) + work)
            heat.append(queued)
        return statistics.median(latencies), robust_error(latencies), statistics.median(heat)

    def _order(self, servers, kind, now):
        self.sends[kind].append(now)
        fresh = dict((s, self.probes[s]) for s in servers
                     if s in self.probes and now - self.probes[s].at <= MAX_AGE)
        if not fresh:
            if self.current not in servers:
                self._move(self.rng.choice(servers), 'unknown', 'no answer yet: at random')
            return [self.current] + [s for s in servers if s != self.current]
        rate = self.rate(kind, now)
        estimates = dict((s, self.estimate(a, kind, fresh, rate)) for s, a in fresh.items())
        latency = dict((s, e[0]) for s, e in estimates.items())
        self.errors = dict((s, e[1]) for s, e in estimates.items())
        rifs = dict((s, e[2]) for s, e in estimates.items())       # work in flight
        limit = quantile(list(rifs.values()), HOT_QUANTILE)
        cold = [s for s in fresh if rifs[s] <= limit]
        choice = self._choose(cold, latency, rifs)
        ranked = sorted(fresh, key=lambda s: (s not in cold, latency[s] if s in cold
                                              else rifs[s]))
        ranked.remove(choice)
        return [choice] + ranked + [s for s in servers if s not in fresh]

    def noise(self, a, b):
        """What a difference of the latencies of servers ``a`` and ``b`` must exceed."""
        ea, eb = self.errors.get(a, 0.0), self.errors.get(b, 0.0)
        return Z * math.sqrt(ea * ea + eb * eb)

    def _move(self, server, reason, why):
        """Go to ``server``; ``reason`` counts in :attr:`moves`, ``why`` says it."""
        if server != self.current:
            self.moves[reason] += 1
            self.current, self.why = server, why
        return server

    def _choose(self, cold, latency, rifs):
        here = self.current
        if not cold:      # every candidate hot (cannot happen with a strict quantile: kept)
            return self._move(min(rifs, key=lambda s: (rifs[s], latency[s])), 'all hot',
                              'every server hot: the fewest in flight')
        best = min(cold, key=lambda s: latency[s])
        if here in cold and latency[here] - latency[best] <= self.noise(here, best):
            return here
        near = [s for s in cold if latency[s] - latency[best] <= self.noise(s, best)]
        choice = self.rng.choice(sorted(near))
        if here not in latency:
            return self._move(choice, 'gone' if here is not None else 'first',
                              'server %s not usable: the fastest cold server' % here
                              if here is not None else 'the fastest cold server')
        if here not in cold:
            return self._move(choice, 'hot', 'server %s hot (%.3g s of work in flight per '
                              'worker, above the %.2g quantile)'
                              % (here, rifs[here], HOT_QUANTILE))
        return self._move(choice, 'faster', 'server %s faster than %s by %.3g ms' % (
            best, here, 1e3 * (latency[here] - latency[best])))
