"""When a robot probes each of its servers: uniformly, or adaptively (no rospy).

A choice is decided by the few servers near the best: the robot's *contenders*, which its
per-task rule names from its own estimates (``Balancer.contenders``). Adaptive probing
samples those often and the rest rarely: a server far from the best needs a probe now and
then only to notice that it came near.

:class:`ProbePlan` gives each server's next probe time. Contenders are probed at
``contender_rate`` each, together at most ``budget`` probes a second (a near-equal fleet
has many contenders) and ``per_task`` probes per task the robot sends (four equally near
servers are all contenders; a robot sending 2 tasks a second probes them at 2 Hz each,
not 4), never below ``background_rate``, all of them in one round: their
round trips are compared under one load of the robot's host and network, and a round
costs the robot one batch whatever its size; the others at ``background_rate``, their
phases spread over the period so that they do not come in one burst. A server stays a
contender for ``hold`` s after it last was one. Without a ``contender_rate`` the plan is
uniform: every server every ``1/rate`` s, in rounds (the paper: 1 Hz).

The robot asks :meth:`ProbePlan.due` when :meth:`ProbePlan.next_time` comes and probes
what it returns as one round (servers due within half a ``tick`` go together); the
manager sees the same uneven rounds in the robot's sample batches.
"""

import math
import threading


GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0     # phases i x GOLDEN mod 1 spread evenly
PROBES_PER_TASK = 4.0    # the contenders' probes per task of the robot, together, at most


class ProbePlan(object):
    """Each server's next probe time (see the module's docstring). Not thread-safe: one
    timer drives it. Times are the caller's clock (s)."""

    def __init__(self, rate=1.0, contender_rate=0.0, background_rate=0.5, budget=20.0,
                 hold=1.0, per_task=PROBES_PER_TASK):
        for name, value in (('rate', rate), ('background_rate', background_rate),
                            ('budget', budget)):
            if not value > 0:
                raise ValueError('%s must be positive, got %r' % (name, value))
        if contender_rate and contender_rate < background_rate:
            raise ValueError('contender_rate %r is below background_rate %r'
                             % (contender_rate, background_rate))
        self.adaptive = bool(contender_rate)
        self.contender_rate, self.background_rate = float(contender_rate), float(background_rate)
        self.budget, self.hold = float(budget), float(hold)
        self.per_task = float(per_task)
        self._task_rate = None   # the robot's tasks a second (None: not known)
        self.tick = 1.0 / (contender_rate if self.adaptive else rate)
        self._next = {}          # server -> when it is due
        self._until = {}         # contender -> until when it stays one
        self._beat = None        # when the contenders' next round is due

    @property
    def servers(self):
        return sorted(self._next)

    @property
    def contenders(self):
        return sorted(self._until) if self.adaptive else self.servers

    def add(self, server, now):
        """A new server: due at once (a contender until it has been sampled)."""
        if server not in self._next:
            self._next[server] = now
            if self.adaptive:
                self._until[server] = now + self.hold

    def remove(self, server):
        self._next.pop(server, None)
        self._until.pop(server, None)

    def describe(self):
        if not self.adaptive:
            return 'at %.3g Hz' % (1.0 / self.tick)
        return 'contenders at %.3g Hz (%.3g Hz in all), the others at %.3g Hz' % (
            self.contender_rate, self.budget, self.background_rate)

    def interval(self, server):
        """Seconds between two probes of ``server`` now."""
        if not self.adaptive:
            return self.tick
        if server in self._until:       # the contenders share what they may take together
            together = self.budget
            if self.per_task and self._task_rate is not None:
                together = min(together, self.per_task * self._task_rate)
            share = min(self.contender_rate, together / len(self._until))
            return 1.0 / max(self.background_rate, share)
        return 1.0 / self.background_rate

    def rate(self):
        """Probes per second now, all servers together."""
        return sum(1.0 / self.interval(s) for s in self._next)

    def update(self, contenders, now, task_rate=None):
        """The contenders now (the rule's): they become (or stay) contenders for ``hold``
        s; those whose hold has ended are demoted to the background, their next probe
        within one background period, at a phase of their own (servers demoted together
        are not probed together). ``task_rate``: the robot's tasks a second, which the
        contenders' probes follow (``per_task`` in all; None: not known)."""
        if not self.adaptive:
            return
        self._task_rate = task_rate
        for server in contenders:
            if server in self._next:
                self.promote(server, now, at_once=False)
        for server, until in list(self._until.items()):
            if until <= now and server not in contenders:
                del self._until[server]
                self._next[server] = now + (server * GOLDEN) % 1.0 / self.background_rate

    def promote(self, server, now, at_once=True):
        """``server`` is a contender from now on (for ``hold`` s); ``at_once``: probe it
        at the next tick (a fast re-check)."""
        if not self.adaptive or server not in self._next:
            return
        was = server in self._until
        self._until[server] = now + self.hold
        if at_once and not was:
            self._next[server] = now
        elif not was:
            self._next[server] = min(self._next[server], self._beat_after(now))

    def _beat_step(self):
        """Seconds between two of the contenders' rounds (one tick while there is none)."""
        return self.interval(next(iter(self._until))) if self._until else self.tick

    def _beat_after(self, now):
        """The contenders' next round: their beat, started now when there is none."""
        if self._beat is None or self._beat < now - self.tick / 2.0:
            self._beat = now + self._beat_step()
        return self._beat

    def next_time(self):
        """When :meth:`due` next has a server to return (None: no server)."""
        if not self._next:
            return None
        return min(self._next.values()) - (self.tick / 2.0 if self.adaptive else 0.0)

    def due(self, now):
        """The servers to probe at this tick (``now``), sorted; each one's next probe is
        moved one interval on (from ``now`` when it fell more than one behind)."""
        if not self.adaptive:
            servers = self.servers
            for server in servers:
                self._next[server] = now + self.tick
            return servers
        due, soon = [], now + self.tick / 2.0
        if self._beat is not None and self._beat <= soon:     # the contenders' round
            step = self._beat_step()
            self._beat = self._beat + step if self._beat + step > now else now + step
        for server, when in self._next.items():
            if when <= soon:
                due.append(server)
                if server in self._until:       # on the beat from now on
                    self._next[server] = self._beat_after(now)
                    continue
                step = self.interval(server)
                self._next[server] = when + step if when + step > now else now + step
        return sorted(due)


def from_params(get):
    """The :class:`ProbePlan` that parameters ask for (``get(name)``: ``probe_rate``,
    ``contender_rate``, ``background_rate``, ``contender_budget``, ``window``)."""
    return ProbePlan(get('probe_rate'), get('contender_rate'), get('background_rate'),
                     get('contender_budget'), hold=get('window'))


class ProbeRound(object):
    """The samples of one probe round of a robot (thread-safe: its probes end on many
    threads), published as one batch when the last one is in."""

    def __init__(self, number, stamp, servers):
        self.number, self.stamp = number, stamp
        self.waiting = set(servers)
        self.samples = []
        self.lock = threading.Lock()

    def record(self, server, ok, rtt, wait):
        """Add a sample; True when it completes the round."""
        with self.lock:
            self.samples.append((server, ok, rtt if ok else 0.0, wait or 0.0))
            self.waiting.discard(server)
            return not self.waiting
