"""What every per-task rule keeps (no rospy): :class:`Balancer`, the state a robot's rule
is told (its attempts out per server, each server's newest probe answer, a random source).
The rules build on it: the league's peers (:mod:`balancers`) and the fleet profile's
``least_latency`` (:mod:`least_latency`).
"""

import collections
import random
import threading
import time

from server_select.core.rule.estimates import MECHANISMS, SendRate, ServerEstimates


ProbeAnswer = collections.namedtuple('ProbeAnswer',
                                     'server rtt rif service workers at utilization '
                                     'service_error')
ProbeAnswer.__doc__ = """One probe answer as a balancer keeps it: round trip (s), requests
in flight (queued + in service), ``{kind: work s}``, workers, when it arrived, the
share of the workers' time the other robots' tasks take, and ``{kind: the standard error
of the work}``."""


class Order(list):
    """The servers in a rule's order for the next task (the first gets it), with
    ``reasons``: ``{server: why the rule named it}`` (empty: a peer's go unexplained). A
    rule's answer to an ask: what it will do when the task is sent (:meth:`Balancer.started`
    with this order) is decided here, and asking changes nothing."""

    def __init__(self, servers, reasons=None):
        list.__init__(self, servers)
        self.reasons = reasons or {}


Decision = collections.namedtuple('Decision', 'server reason estimates')
Decision.__doc__ = """Where a task would go and why, with what the rule compared: ``{server:
its estimate}`` (None: no answer in the window). The fleet's rule's ``choose`` returns one."""


class Balancer(object):
    """The state every peer keeps: this robot's attempts out per server, the newest probe
    answer of each, and a random source (``rng``), drawn from once per task (``draw``:
    the next decision's numbers, so that asking draws nothing); ``sends``: the robot's
    :class:`~server_select.core.rule.estimates.SendRate`, which the robot feeds (None: the
    rule counts its own attempts, as a rule made alone). Each kind of task goes where the
    rule sends that kind (:attr:`chosen_for`): a robot sending frames and sort tasks may be
    served best by two servers, and a frame sent to one is no move of its sort tasks.
    Every rule keeps :attr:`estimates` of its servers from the answers of the last
    ``window`` s (``mechanisms``: the estimate's parts in use), the one load model the
    robot's attempt deadlines follow whichever rule chooses. Thread-safe."""

    name = None
    copies = 1
    own_view = False     # whether it ranks the servers by estimates of its own (view())

    def __init__(self, rng=None, clock=time.monotonic, sends=None, window=1.5,
                 mechanisms=MECHANISMS):
        self.rng = rng or random.Random()
        self._clock = clock
        self.sends = sends or SendRate(clock)
        self._counts_sends = sends is None
        self._lock = threading.RLock()    # (ordering asks fresh limits: estimates)
        self.attempts_out = collections.Counter()     # server -> this robot's attempts out there
        self.probes = {}                     # server -> its newest ProbeAnswer
        self.chosen_for = {}                 # kind -> where its last task went
        self.reason_for = {}                 # kind -> why its tasks go there
        self._main = None                    # the kind the robot sent most of lately
        self.on_move = None                  # on_move(server, why, kind): kind's tasks moved
        # what the robot expects of each server: what attempts' deadlines follow for every rule
        self.estimates = ServerEstimates(window, self.sends, self.chosen_for, mechanisms)
        self.next_draw = self._draws()

    @property
    def window(self):
        """Seconds of probe answers an estimate rests on (a live setting)."""
        return self.estimates.window

    @window.setter
    def window(self, seconds):
        self.estimates.window = float(seconds)

    def _draws(self):
        """The random numbers a decision may use (two: a pair of servers)."""
        return self.rng.random(), self.rng.random()

    def probed(self, server, rtt, load=None):
        """A good probe answer: round trip ``rtt`` and ``load`` (a Load, or None)."""
        answer = ProbeAnswer(server, rtt, (load.queued + load.in_service) if load else 0,
                             dict(load.service) if load else {},
                             max(1, load.workers) if load else 1, self._clock(),
                             load.utilization if load else 0.0,
                             dict(load.service_error or {}) if load else {})
        with self._lock:
            self.probes[server] = answer
            self.estimates.heard(answer, max(0, answer.rif - self.attempts_out[server]))
            self._probed(answer)

    def answer_wait(self, server, kind):
        """What the newest answer of ``server`` says a ``kind`` task waits and works there
        (s; None: none): :meth:`ServerEstimates.answer_wait`."""
        with self._lock:
            return self.estimates.answer_wait(server, kind)

    def attempt_seconds(self, kind, server):
        """What one attempt of a ``kind`` task takes at ``server`` by the estimate now (round
        trip + wait + work, not the tries a rule ranks an overloaded server by; None:
        unknown): what an attempt's deadline follows."""
        estimate = self._estimate_now(server, kind)
        return None if estimate is None else estimate.rtt + estimate.wait + estimate.work

    def fresh_seconds(self, kind, factor, period, server):
        """How long a ``kind`` task (a camera frame, one every ``period()`` s) is worth
        waiting for at ``server``: until the next frame is due, and at least ``factor`` x
        (round trip + work) there with no queue (None: unknown)."""
        estimate = self._estimate_now(server, kind)
        if estimate is None or not estimate.work > 0:
            return None
        return max(period(), factor * (estimate.rtt + estimate.work))

    def _estimate_now(self, server, kind):
        with self._lock:
            return self.estimates.estimate(server, kind, self._clock())

    def _probed(self, answer):
        """Subclasses: a probe answer arrived (lock held)."""

    def started(self, server, kind=None, first=True, order=None):
        """An attempt of a ``kind`` task is sent to ``server``; the ``first`` of a task,
        chosen from ``order`` (what :meth:`order` answered), makes it where tasks go, for
        the reason the order gave (asking :meth:`order` is not sending: a robot may ask
        where a task would go)."""
        moved = None
        if self._counts_sends:
            self.sends.started(server, kind)
        with self._lock:
            now = self._clock()
            self.attempts_out[server] += 1
            self._started(server, kind, now)
            if first and order is not None:
                self._chosen(server, kind, now, order)
            if first:       # a decision's draw is spent (a re-send or a hedge takes the next
                self.next_draw = self._draws()    # in the order, and draws nothing)
            said = getattr(order, 'reasons', {}).get(server) if first else None
            if first and kind != self._main:
                self._main = self._main_kind(now, kind)
            if first and server != self.chosen_for.get(kind):
                moved = said                          # (a peer's: unexplained)
                self.chosen_for[kind], self.reason_for[kind] = server, said or ''
            elif said:      # kept: why, as the last decision said ("kept: the fastest")
                self.reason_for[kind] = said
        if moved is not None and self.on_move is not None:
            self.on_move(server, moved, kind)

    @property
    def chosen(self):
        """Where the robot's tasks go: those of the kind it sent most of lately (None: none
        sent yet)."""
        return self.chosen_for.get(self._main)

    @property
    def reason(self):
        """Why :attr:`chosen` (the last decision's reason for that kind)."""
        return self.reason_for.get(self._main, '')

    def _main_kind(self, now, sent=None):
        """The kind the robot sent most of lately (``sent``, the one just sent, when none
        is counted yet)."""
        counts = dict((k, self.sends.count(k, now)) for k in self.sends.kinds())
        if not any(counts.values()):
            return sent
        return max(sorted(counts, key=str), key=counts.get)

    def _started(self, server, kind, now):
        """Subclasses: an attempt was sent (lock held)."""

    def _chosen(self, server, kind, now, order):
        """Subclasses: a task's first attempt went to ``server``, chosen from ``order``
        (lock held): what the choice changes in the rule's own state."""

    def ended(self, server, rtt=None):
        """An attempt at ``server`` ended: ``rtt`` its round trip (answered, or failed
        after that long), None when it just stopped counting (another attempt won)."""
        with self._lock:
            if self.attempts_out[server] > 0:
                self.attempts_out[server] -= 1
            if rtt is not None:
                self._ended(server, rtt, self._clock())

    def _ended(self, server, rtt, now):
        """Subclasses: an attempt's round trip (lock held)."""

    def order(self, servers, kind=None, fresh=None):
        """``servers`` (the usable ones) in this rule's order for the next ``kind`` task
        (the first gets it; re-sends and hedges take the next). ``fresh(server)``: how long
        a ``kind`` task's answer from there is worth having (s; None: unknown); servers
        the rule expects to answer later than that come after the others, in its order."""
        servers = list(servers)
        if not servers:
            return Order([])
        with self._lock:
            now = self._clock()
            late = self._late(servers, kind, now, fresh) if fresh is not None else []
            if not late or len(late) == len(servers):
                ordered = self._order(servers, kind, now)
            else:
                ordered = self._order([s for s in servers if s not in late], kind, now)
                stale = ', '.join(str(server) for server in late)
                ordered = Order(list(ordered) + self._order(late, kind, now), dict(
                    (s, '%s (server %s: an answer after the task is stale)' % (why, stale))
                    for s, why in getattr(ordered, 'reasons', {}).items()))
        return ordered if isinstance(ordered, Order) else Order(ordered)

    def _order(self, servers, kind, now):
        raise NotImplementedError

    def _late(self, servers, kind, now, fresh):
        """Subclasses: the ``servers`` whose ``kind`` answer the rule expects after
        ``fresh(server)`` s (lock held; a rule without estimates: none)."""
        return []

    def contenders(self, servers):
        """The servers worth probing often: all of them (a rule with estimates of its own
        names fewer)."""
        return set(servers)

    def task_rate(self):
        """The robot's tasks a second lately (None: this rule does not count them)."""
        return None

    def view(self, servers):
        """The robot's ranking by this rule's own estimates (rules with ``own_view``)."""
        raise NotImplementedError

    def _two(self, servers):
        """Two distinct servers drawn at random (one when there is one), by ``draw``."""
        first = int(self.next_draw[0] * len(servers))
        if len(servers) == 1:
            return [servers[first]]
        second = int(self.next_draw[1] * (len(servers) - 1))
        return [servers[first], servers[second + (second >= first)]]
