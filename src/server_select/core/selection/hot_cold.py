"""The fleet profile's selection rule, ``hot_cold`` (no rospy): Prequal's lexicographic
comparison (avoid the hot, then take the fastest), made sticky for robots.

Per task, from the robot's own evidence (a :class:`~server_select.core.selection.balancer.Balancer`:
the robot tells it its probe answers, its attempts, and the kind of task it sends):

1. The candidates are the servers the robot's health has not ejected (the caller's list).
2. A server's *latency* for a task of a kind is its *expected completion*, from each of
   its probe answers of the robot's window (``~window``, at least its newest
   :data:`MIN_ANSWERS`): the robot's round trip + the other robots' work in flight there
   (their requests queued and in service x the work per task of the kind, per worker:
   what a task sent then would wait for) + the work (the median of what the servers
   report, where it has done none yet); the mean of those, its noise their standard
   error, counting answers closer together than a task's work as one (they saw much the
   same queue), and the error of the work itself (a server reports the median of its
   recent tasks' work and that median's standard error: two equal servers' medians
   differ by a few per cent, and robots moved for that and back). Not the robot's own
   task round trips (docs/selection.md says why). Robots keep a task or two out each:
   servers and robots make a closed system, a task waits for the work in flight ahead.
   A server asked for more work than it can do (the utilization of the others' announced
   rates plus the robot's own above 1) does 1/u of it and answers the rest busy: a task
   there takes u times as long to get through (its short queue alone would look fast).
3. A server is *hot* when the others' work in flight per worker (the median over its
   answers of the window) is above the 2^-0.25 quantile of the candidates' (Prequal's rule, on work
   rather than on requests: servers of unequal speed carry unequal numbers of requests);
   the robot's own server only when it is above by more than one task's work (whether an
   answer caught another robot's task in service or not is no reason to move).
4. The robot **keeps** the server its last task went to while that server is cold and no
   cold server's latency is lower by more than the noise of the comparison: 3 standard
   errors of the difference of the two latencies. Else it takes a cold server of the
   lowest latency, at random among those within that noise of it (robots that see the
   same servers do not all move to one); every candidate hot: the least work in flight;
   no answer yet from any candidate: one at random (Prequal with fewer than 2 answers),
   which also spreads robots that start together.
5. Robots on one server read the same answers, a window old, and would leave it together
   and herd. So a robot that would leave a server it can still use moves with a
   probability: the share of the robots like it there (the others' utilization over its
   own, itself included) whose moving makes the two servers' latencies meet (each as
   step 2 has it, with that many robots like this one more or fewer), spread over the
   tasks it sends in a window (the time its answers take to show who moved); 1 where the
   move pays even if all of them make it (a robot whose own load is small beside the
   server's: every network change). Staying, it asks again with its next task. (Agents
   routing on stale information settle when each moves with a probability that shrinks
   with what their moving together would change, and oscillate when all move at once:
   Fischer and Vöcking, "Adaptive routing with stale information", PODC 2005.)

Adapted from Prequal (NSDI '24) for robots: latency is the robot's own round trip plus the
server's expected wait and work (a robot's network differs per server; a web client's does
not), requests in flight leave out the robot's own (a robot with one task out would see its
own server one task hotter than the rest and leave it for nothing), requests count by
their work (servers differ in speed), each server's answers of the window stand for the
pool (a robot probes every server several times a second), and the choice is kept while
nothing beats it (a move is a new connection and a cold start at the server). No
parameter of its own: the quantile and the 3 errors are the rule's; the window is the
robot's ``~window``.
"""

import collections
import math
import statistics

from server_select.core.selection.balancer import Balancer
from server_select.core.util.stats import mean_error, percentile

MIN_ANSWERS = 3          # answers per server kept however old (a rarely probed server)
KEEP = 64                # answers kept per server at most
HOT_QUANTILE = 2 ** -0.25
Z = 3.0                  # standard errors a challenger must win by
MAX_AGE = 3.0            # s: an older probe answer does not count (the probes stopped)
RATE_HORIZON = 5.0       # s of the robot's own tasks its rate is counted over
MAX_ALIKE = 1000         # robots like this one a server is counted to have at most


Answer = collections.namedtuple('Answer', 'rtt others utilization')


class HotCold(Balancer):
    """The ``hot_cold`` rule (the module docstring says what it does)."""
    name = 'hot_cold'

    def __init__(self, window=1.5, **kwargs):
        Balancer.__init__(self, **kwargs)
        self.window = float(window)
        # server -> (time, Answer) of its answers: round trip, the others' requests in
        # flight, their share of the workers' time
        self.answers = collections.defaultdict(lambda: collections.deque(maxlen=KEEP))
        self.current = None
        self.why = 'no task yet'
        self.sends = collections.defaultdict(collections.deque)   # kind -> its task times
        self.moves = collections.Counter()     # why the robot changed server, how often
        self.errors = {}                       # server -> its latency's standard error
        self.on_move = None                    # on_move(server, why): a move was made

    def _probed(self, answer):
        others = max(0, answer.rif - self.out[answer.server])
        self.answers[answer.server].append(
            (answer.at, Answer(answer.rtt, others, answer.utilization)))

    def _window(self, entries, now, keep=0):
        """The ``entries`` ((time, value), oldest first) of the last window, and at
        least the newest ``keep``."""
        recent = [(t, v) for t, v in entries if now - t <= self.window]
        return recent if len(recent) >= keep else list(entries)[-keep:]

    def _recent(self, entries, now, keep=0):
        """The values of :meth:`_window`."""
        return [v for _, v in self._window(entries, now, keep)]

    def _work(self, answer, kind, fresh):
        if kind in answer.service:
            return answer.service[kind]
        known = [a.service[kind] for a in fresh.values() if kind in a.service]
        return statistics.median(known) if known else 0.0

    def _started(self, server, kind, now):
        self.sends[kind].append(now)

    def rate(self, kind, now):
        """The robot's ``kind`` tasks per second over the last :data:`RATE_HORIZON` s,
        the one it decides for included: their count over the horizon. Bounded: two
        attempts 10 ms apart (one sent on after a busy answer) do not make it 100 a
        second, an own load that swamped every server alike and kept the robot where it
        was; and never 0 (its own load unknown: it would move for certain). Attempts
        count when sent (:meth:`started`), not when the robot asks where one would go."""
        times = self.sends[kind]
        while times and now - times[0] > RATE_HORIZON:
            times.popleft()
        return (len(times) + 1) / RATE_HORIZON

    def estimate(self, newest, kind, fresh, rate=0.0, alike=1, now=None):
        """``(latency, its standard error, work in flight per worker, a task's work per
        worker)`` of a ``kind`` task at ``newest``'s server (its newest answer), from
        each of the server's answers of the last window (at least :data:`MIN_ANSWERS`):
        round trip + the others' work in flight there per worker (what a task sent then
        would wait for) + the work, x the tries at the utilization; the mean of those
        and its standard error (with the error of the server's reported work), and the
        median of the work in flight. ``alike``: the
        robots like this one (its ``rate`` x the work, and what such a robot keeps in
        flight) the server is judged with, this one included: 1 as the answers show it,
        k with k - 1 more arriving, 2 - k with k - 1 of the others leaving."""
        work = self._work(newest, kind, fresh)
        work_error = newest.service_error.get(kind, 0.0) if kind in newest.service else 0.0
        workers = float(newest.workers)
        mine = rate * work / workers
        extra = (alike - 1) * mine * work
        now = newest.at if now is None else now
        latencies, heat, per_work = [], [], []
        entries = self._window(self.answers[newest.server], now, MIN_ANSWERS)
        for a in [a for _, a in entries] or [Answer(newest.rtt, 0, newest.utilization)]:
            queued = a.others * work / workers
            # asked for more than it can do, a server does 1/u of it: a task gets through
            # in u tries (busy answers, re-sends), in expectation
            tries = max(1.0, a.utilization + mine * alike)
            latencies.append((a.rtt + max(0.0, queued + extra) + work) * tries)
            heat.append(queued)
            per_work.append((1.0 + a.others / workers) * tries)   # d latency / d work
        # answers closer together than a task's work see much the same queue: about one
        # a task's work over their span is independent of the others
        span = entries[-1][0] - entries[0][0] if entries else 0.0
        independent = 1.0 + span * workers / work if work > 0 else None
        mean, error = mean_error(latencies, independent)
        # the work (a median of the server's recent tasks) has an error every answer shares
        error = math.hypot(error, work_error * statistics.fmean(per_work))
        return mean, error, statistics.median(heat), work / workers

    def share(self, here, there, kind, fresh, rate, now):
        """The probability that this robot, one of those like it at ``here``, moves to
        ``there`` with this task (the module docstring's step 5)."""
        newest = fresh[here]
        mine = rate * self._work(newest, kind, fresh) / float(newest.workers)
        if mine <= 0.0:
            return 1.0                         # its own load unknown yet
        others = [a.utilization for a in
                  self._recent(self.answers[here], now, MIN_ANSWERS)] or [0.0]
        alike = min(MAX_ALIKE, 1.0 + statistics.fmean(others) / mine)

        def pays(k):
            return (self.estimate(fresh[there], kind, fresh, rate, k, now)[0] <=
                    self.estimate(newest, kind, fresh, rate, 2 - k, now)[0])
        if pays(alike):
            return 1.0
        low, high = 1, max(1, int(math.ceil(alike)) - 1)     # the move pays alone: low
        while low < high:
            middle = (low + high + 1) // 2
            low, high = (middle, high) if pays(middle) else (low, middle - 1)
        return low / alike / max(1.0, rate * self.window)

    def _order(self, servers, kind, now):
        fresh = dict((s, self.probes[s]) for s in servers
                     if s in self.probes and now - self.probes[s].at <= MAX_AGE)
        if not fresh:
            if self.current not in servers:
                self._move(self.rng.choice(servers), 'unknown', 'no answer yet: at random')
            return [self.current] + [s for s in servers if s != self.current]
        rate = self.rate(kind, now)
        estimates = dict((s, self.estimate(a, kind, fresh, rate, now=now))
                         for s, a in fresh.items())
        latency = dict((s, e[0]) for s, e in estimates.items())
        self.errors = dict((s, e[1]) for s, e in estimates.items())
        rifs = dict((s, e[2]) for s, e in estimates.items())       # work in flight
        limit = percentile(sorted(rifs.values()), 100 * HOT_QUANTILE)
        # the robot's own server is hot only by one more task than that: a single answer
        # that caught another robot's task is not a reason to move
        cold = [s for s in fresh if rifs[s] <= limit +
                (estimates[s][3] if s == self.current else 0.0)]
        choice = self._choose(cold, latency, rifs, lambda there: self.share(
            self.current, there, kind, fresh, rate, now))
        ranked = sorted(fresh, key=lambda s: (s not in cold, latency[s] if s in cold
                                              else rifs[s]))
        ranked.remove(choice)
        return [choice] + ranked + [s for s in servers if s not in fresh]

    def noise(self, a, b):
        """What a difference of the latencies of servers ``a`` and ``b`` must exceed."""
        ea, eb = self.errors.get(a, 0.0), self.errors.get(b, 0.0)
        return Z * math.sqrt(ea * ea + eb * eb)

    def _move(self, server, reason, why):
        """Go to ``server``; ``reason`` counts in :attr:`moves`, ``why`` says it (and
        :attr:`on_move`, when set, hears both)."""
        if server != self.current:
            self.moves[reason] += 1
            self.current, self.why = server, why
            if self.on_move is not None:
                self.on_move(server, why)
        return server

    def _choose(self, cold, latency, rifs, share):
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
        if self.rng.random() >= share(choice):
            return here          # this time, one of the others like it moves
        if here not in cold:
            return self._move(choice, 'hot', 'server %s hot (%.3g s of work in flight per '
                              'worker, above the %.2g quantile)'
                              % (here, rifs[here], HOT_QUANTILE))
        return self._move(choice, 'faster', 'server %s faster than %s by %.3g ms' % (
            best, here, 1e3 * (latency[here] - latency[best])))
