"""A robot's own evidence about its servers (no rospy): eject on failure, probation on return.

A failed probe, a task without answer by its deadline or an error result ejects that
server from the robot's candidates at once, for an ejection time that doubles with each
ejection in a row (``base`` s, at most ``longest`` s; as Envoy's outlier detection). When
the time is over the server is on probation: it becomes a candidate again after
``probation_probes`` good probes, and its first good task makes it healthy (the ejection
time starts from ``base`` again); a failure on probation ejects it for twice as long.
A server ejected because its *probes* failed (its link down, its host stopped) is on
probation as soon as ``probation_probes`` probes in a row are answered again: the
evidence that ejected it is gone (after a 20 s outage, the doubled time would otherwise
keep a server that is back out for up to ``longest`` s more), and the outage counts as one
ejection: a task that fails on its return (one sent into a connection the outage left
stalled) ejects it for 2 x ``base`` s, not for the outage's doubled time. One ejected
because its tasks failed serves its time: its probes may answer while its tasks do not.

A server that has never answered is not failing but not up yet (a host still starting,
a server launched later): its failures do not eject it with a growing time, which would
keep it out for up to ``longest`` s after it came up; it is *down* until its first
``probation_probes`` good probes make it a candidate. Once it has answered, its failures
eject it as above.

A server that answers *busy* is working, not failing: it is not ejected, but goes behind
every server that is not busy for ``seconds`` (what its load says it needs to catch up),
and stays a candidate for when all of them are busy.

When no server is usable, the ejected ones whose last probe was answered are used anyway
(Envoy's *panic threshold*, at 0 %: a fleet that still answers some tasks when degraded
serves more by trying than by failing every task at once). A task late on a host that is
slow for a moment, on every server in turn, would otherwise leave the robot nothing to
send to for an ejection time; a server whose probes fail stays out.

No news is not bad news: when the ranking names no server (no sample in the window, as
after the robot, or its manager, stalled for longer than the window), tasks go on to the
server they went to, as far as this evidence allows. A robot on a busy host would
otherwise fail every task between waking and its next probe's answer.
"""

import collections
import threading
import time

HEALTHY, EJECTED, PROBATION, DOWN = 'healthy', 'ejected', 'probation', 'down'

Ejection = collections.namedtuple('Ejection', 'server seconds why')


class _Server(object):
    __slots__ = ('state', 'until', 'ejections', 'good_probes', 'busy_until', 'answered',
                 'by_probe', 'reachable')

    def __init__(self):
        self.state, self.until, self.ejections, self.good_probes = HEALTHY, 0.0, 0, 0
        self.busy_until = 0.0
        self.answered = False
        self.by_probe = False   # the last ejection was for a failed probe
        self.reachable = False  # its last probe was answered


class ServerHealth(object):
    """Health of each of a robot's servers; thread-safe."""

    def __init__(self, servers, base=1.0, longest=30.0, probation_probes=2,
                 clock=time.monotonic):
        if not 0 < base <= longest:
            raise ValueError('need 0 < base <= longest, got %r, %r' % (base, longest))
        self.base, self.longest = float(base), float(longest)
        self.probation_probes = int(probation_probes)
        self._clock = clock
        self._lock = threading.Lock()
        self._servers = dict((s, _Server()) for s in servers)
        self._first = None     # where the last task went first

    def add(self, server):
        """A new server: healthy."""
        with self._lock:
            self._servers.setdefault(server, _Server())

    def remove(self, server):
        """A server that left: never usable."""
        with self._lock:
            self._servers.pop(server, None)

    def _get(self, server, now):
        entry = self._servers.get(server)
        if entry is not None and entry.state == EJECTED and now >= entry.until:
            entry.state, entry.good_probes = PROBATION, 0
        return entry

    def failure(self, server, why='', probe=False, late=False):
        """Evidence that ``server`` failed (``probe``: a probe of it did; ``late``: a
        probe of it is still out past its time, which ejects it as a failed probe does
        but says nothing yet of whether it is reachable: on a loaded host a busy server
        answers late, and when it is the only one the panic rule keeps sending to it): an
        :class:`Ejection` if this ejects it (of 0 s when it makes a server that never
        answered *down*), else None (an unknown server, or one already ejected or down)."""
        probe = probe or late
        with self._lock:
            entry = self._get(server, self._clock())
            if entry is not None and probe and not late:
                entry.reachable = False
            if entry is not None and entry.state == EJECTED:
                entry.good_probes = 0           # answers since must be in a row
                entry.by_probe = entry.by_probe and probe
            if entry is None or entry.state == EJECTED:
                return None
            if not entry.answered:
                first, entry.state, entry.good_probes = entry.state != DOWN, DOWN, 0
                return Ejection(server, 0.0, why) if first else None
            entry.ejections += 1
            seconds = min(self.longest, self.base * 2 ** (entry.ejections - 1))
            entry.state, entry.until, entry.good_probes = EJECTED, self._clock() + seconds, 0
            entry.by_probe = probe
            return Ejection(server, seconds, why)

    def busy(self, server, seconds):
        """``server`` answered busy: behind the servers that are not, for ``seconds``."""
        with self._lock:
            entry = self._servers.get(server)
            if entry is not None:
                entry.busy_until = max(entry.busy_until, self._clock() + seconds)

    def probe_ok(self, server):
        with self._lock:
            entry = self._get(server, self._clock())
            if entry is not None:
                entry.answered = entry.reachable = True
                if entry.state in (PROBATION, DOWN) or (entry.state == EJECTED and
                                                        entry.by_probe):
                    entry.good_probes += 1
                if entry.by_probe and entry.state in (EJECTED, PROBATION) and \
                        entry.good_probes >= self.probation_probes:
                    entry.state, entry.ejections = PROBATION, 1   # its probes answer again

    def task_ok(self, server):
        """A good answer; True when it ends ``server``'s probation."""
        with self._lock:
            entry = self._get(server, self._clock())
            if entry is not None:
                entry.answered = True
            if entry is None or entry.state not in (PROBATION, DOWN):
                return False
            entry.state, entry.ejections = HEALTHY, 0
            return True

    def state(self, server):
        with self._lock:
            entry = self._get(server, self._clock())
            return entry.state if entry is not None else None

    def usable(self, server):
        """Whether tasks may go to ``server`` now."""
        with self._lock:
            entry = self._get(server, self._clock())
            return entry is not None and (entry.state == HEALTHY or (
                entry.state in (PROBATION, DOWN)
                and entry.good_probes >= self.probation_probes))

    def order(self, ranking):
        """``ranking`` without the servers tasks may not go to now, those that answered
        busy lately last (order kept otherwise); when none of them may, those ejected
        whose last probe was answered (panic), in the ranking's order. An empty
        ``ranking`` (no sample in the window: the robot, or its manager, stalled for
        longer) stands for the server the last task went to: no news of a server is not
        news against it. Asking changes nothing."""
        with self._lock:
            ranking = ranking or [s for s in [self._first] if s is not None]
        usable = [s for s in ranking if self.usable(s)]
        now = self._clock()
        with self._lock:      # (a server may have left since usable() looked)
            busy = set(s for s in usable if getattr(self._servers.get(s), 'busy_until', 0) > now)
        return [s for s in usable if s not in busy] + [s for s in usable if s in busy] \
            if usable else self.panic(ranking)

    def started(self, server, kind=None, first=True, order=None):
        """An attempt went to ``server`` (a task's ``first``: where tasks go now)."""
        if first:
            with self._lock:
                self._first = server

    def ended(self, server, rtt=None):
        """An attempt ended (nothing to learn here: answers and failures come as
        :meth:`task_ok` and :meth:`failure`)."""

    def panic(self, ranking):
        """The servers of ``ranking`` that are out (ejected, or on probation without its
        probes yet) but answered their last probe: where tasks go when none is usable."""
        with self._lock:
            now = self._clock()
            entries = [(s, self._get(s, now)) for s in ranking]
            return [s for s, e in entries if e is not None and e.reachable and
                    e.state in (EJECTED, PROBATION)]
