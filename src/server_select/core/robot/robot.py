"""A robot of the fleet, whole and without ROS: the one object the robot node drives with
rospy's threads and the simulator drives on its virtual clock.

It owns every decision a robot makes: its probe plan and rounds (a server whose probe is
still out is skipped, and gets a failed sample once that probe is late), the samples and
the health table they feed, the rule and the load view, the servers that join (task
candidates once the transport reaches them) or leave, and a
:class:`~server_select.core.robot.stream.Stream` per task kind (pacing and the task
flow). What it needs from outside comes in as arguments: a ``clock``, a ``stamp`` for
tasks, random sources, a :class:`~server_select.core.robot.world.Transport` and
:class:`~server_select.core.robot.world.Events`. A driver calls :meth:`probe_round` at
:meth:`next_probe_time`, each stream's ``act`` at its ``next_time``, and hands in what
arrives: :meth:`probe_answered`, :meth:`probe_failed`, ``Stream.resolve``,
:meth:`add_server`, :meth:`remove_server`, :meth:`on_flag`.
"""

import itertools
import random
import threading
import time

from server_select.core.flow.budget import RetryBudget
from server_select.core.robot.robot_load import RobotLoad
from server_select.core.robot.probes import ProbeRounds
from server_select.core.robot.stream import Stream
from server_select.core.robot.world import Events, Transport
from server_select.core.robot import probe_plan as probing
from server_select.core.robot.answer_time import STILL_OUT
from server_select.core.ranking.passive import TaskBaseline
from server_select.core.robot.selection_params import robot_selection
from server_select.core.rule.estimates import SendRate


class Robot(object):
    """Robot ``robot_id`` with ``servers`` (its first ones), in ``mode`` (``fixed``: to
    server ``fixed``), its parameters read by ``get(name)``, and one task stream per
    ``(kind, rate)`` of ``kinds`` (a kind: ``kind`` its name, ``newest_wins``, ``make``,
    ``check``, ``run_local``, ``ready()`` and ``input``, as
    :class:`~server_select.ros.plugins.TaskPlugin` has them).

    ``random(purpose)``: the random source for ``'rule'`` (the per-task rule's draws) or
    ``'tasks/<kind>'`` (the stream's phase); ``stamp()``: a task's send stamp; ``limit``:
    tasks a stream sends at most (0: no limit); ``rule_args``: the rule's own (the league's
    ablations). Thread-safe: probe answers, results and the driver's wake-ups may come on
    threads of their own.
    """

    def __init__(self, robot_id, servers, mode, get, kinds, transport=None, events=None,
                 clock=time.monotonic, stamp=None, random=None, fixed=None, limit=0,
                 rule_args=None):
        self.robot_id, self.mode = robot_id, mode
        self.clock, self.stamp = clock, stamp or clock
        self.transport, self.events = transport or Transport(), events or Events()
        self._random = random or _fresh_random
        self.sends = SendRate(clock)     # told of every attempt; the rule and probes read it
        self.selection, self.health, self.policy = robot_selection(
            robot_id, servers, mode, fixed, get, clock=clock, rng=self._random('rule'),
            rule_args=dict(rule_args or {}, sends=self.sends))
        self.balancer = self.selection.balancer
        if self.balancer is not None:
            self.balancer.on_move = lambda server, why, kind: self.events.moved(server, why, kind)
        self.load = RobotLoad(dict((kind.kind, rate) for kind, rate in kinds),
                              self.selection.heading, self.balancer, clock,
                              window=get('window'), sends=self.sends) \
            if get('load_aware') and mode == 'select' else None
        self.baseline = TaskBaseline() if self.selection.passive else None
        self.plan = probing.from_params(get)
        self.rounds = ProbeRounds(self.plan)
        self.probe_timeout = get('probe_timeout')
        self.start_delay = get('start_delay')
        self.joining = set()             # servers that joined, not yet task candidates
        self.budget = RetryBudget(get('retry_budget'), clock=clock)
        ids = itertools.count(1)         # one series of task ids for all the streams
        self.streams = [Stream(self, kind, rate, get, ids, limit) for kind, rate in kinds]
        self._servers = list(servers)
        self._ready_at = 0.0
        self._lock = threading.RLock()

    # -- start and readiness ----------------------------------------------------------------
    def start(self):
        """The robot starts now: its servers due for a probe, its streams paced."""
        now = self.clock()
        with self._lock:
            self.rounds.start(self._servers, now)
            self._ready_at = now + self.start_delay
        for server in self._servers:
            self.transport.connect(server)
        for stream in self.streams:
            stream.start(now)

    def ready(self):
        """Tasks start once ``~start_delay`` has passed and the target is known to be up."""
        return self.clock() >= self._ready_at and self.selection.ready(self.answered)

    @property
    def servers(self):
        with self._lock:
            return self.plan.servers

    @property
    def answered(self):
        """The servers that have answered a probe."""
        return self.rounds.answered

    @property
    def probes(self):
        """Probes sent so far."""
        return self.rounds.sent

    # -- probes ---------------------------------------------------------------------------
    def next_probe_time(self):
        """When the next probe round is due (the clock's time; None: no server)."""
        with self._lock:
            return self.rounds.next_time()

    def probe_round(self):
        """Probe the servers the plan says are due now (one round)."""
        now = self.clock()
        contenders = self.selection.contenders() if self.plan.adaptive else ()
        task_rate = self.selection.task_rate() if self.plan.adaptive else None
        with self._lock:
            due = self.rounds.round(now, contenders, task_rate)
        if due is None:
            return
        number, probes = due
        self.events.round(number, [server for server, _, _ in probes])
        unsent = None
        for server, seq, late in probes:
            if late:      # its previous probe is late: a failed sample, no second call
                self._sample(server, seq, None, STILL_OUT, None, number)
                continue
            try:
                kinds, rates = self.load.announcement(server) if self.load else ((), ())
                handle = self.transport.probe(server, seq, kinds, rates)
            except Exception as error:    # ended failed: left out, it would block the server
                unsent = unsent or error  # for good; the others still go, then it is raised
                self.probe_failed(server, seq, 'probe not sent: %s: %s'
                                  % (type(error).__name__, error))
                continue
            with self._lock:
                self.rounds.sent_with(server, seq, handle)
        if unsent is not None:
            raise unsent

    def probe_answered(self, server, seq, rtt, load=None):
        """Probe ``seq`` of ``server`` was answered (checked, sealed) after ``rtt`` s,
        reporting ``load`` (a :class:`~server_select.core.load.work_queue.Load` or None).
        False: not a probe out (late, or ended already)."""
        with self._lock:
            probe = self.rounds.end(server, seq, rtt)
        if probe is None:
            return False
        wait = self.load.on_answer(server, load, rtt) if self.load is not None else None
        self._sample(server, seq, rtt, '', wait, probe.round)
        return True

    def probe_failed(self, server, seq, error):
        """Probe ``seq`` of ``server`` failed with ``error`` (no answer in time, refused,
        not sealed...). False: not a probe out."""
        with self._lock:
            probe = self.rounds.end(server, seq)
        if probe is None:
            return False
        self._sample(server, seq, None, error, None, probe.round)
        return True

    def _sample(self, server, seq, rtt, error, wait, round_number):
        ok = not error
        self.events.sample(server, seq, rtt, error, wait, round_number)
        try:   # load-aware: the expected completion, round trip + wait
            self.selection.on_sample(server, ok, rtt + wait if ok and wait else rtt,
                                     wait=wait if ok else None)
        except ValueError as err:
            self.events.bad_sample(server, err)
        if not ok:
            self.on_failure(server, 'probe failed: %s' % error, probe=True,
                            late=error == STILL_OUT)
            return
        self.health.probe_ok(server)
        self.transport.heard(server, rtt)     # a connection that lived through an outage
        if self.balancer is not None and self.load is None:
            self.balancer.probed(server, rtt)    # (with a load: from RobotLoad)

    # -- evidence from tasks --------------------------------------------------------------
    def on_failure(self, server, why, probe=False, late=False):
        ejection = self.health.failure(server, why, probe, late)
        if ejection is not None:
            self.events.ejected(server, ejection, why)

    def on_busy(self, kind, server):
        """``server`` refused a ``kind`` task as busy: last of the candidates for as long as
        its load says a task there would take (at least 1 s)."""
        expected = self.load.expected(kind)(server) if self.load is not None else None
        self.health.busy(server, max(1.0, expected or 0.0))

    def on_task_answer(self, kind, server, rtt):
        """A ``kind`` task sent once was answered by ``server`` after ``rtt`` s: with
        ``~passive``, a latency sample less the kind's baseline."""
        with self._lock:
            sample = self.baseline.sample(kind, server, rtt, self.selection.probe_latency(server))
        if sample is not None:
            self.selection.on_sample(server, True, sample, probe=False)
            self.events.task_sample(server, sample)

    def on_flag(self, robot_id, server, ranking):
        """The manager's flag (checked by the driver): None, or why it was refused."""
        return self.selection.on_flag(robot_id, server, ranking)

    # -- servers joining and leaving ------------------------------------------------------
    def add_server(self, server):
        """``server`` joined: probed at once, a task candidate once the transport is wired
        to it (:meth:`admit_joined`)."""
        with self._lock:
            if not self.rounds.add(server, self.clock()):
                return
            self.joining.add(server)
        self.transport.connect(server)
        self.admit_joined()

    def admit_joined(self):
        """Admit the joined servers the transport reaches now (asked again by the driver)."""
        with self._lock:
            ready = [s for s in sorted(self.joining) if self.transport.wired(s)]
            self.joining.difference_update(ready)
        for server in ready:
            self.selection.add_server(server)
        return ready

    def remove_server(self, server):
        """``server`` left the fleet."""
        with self._lock:
            self.joining.discard(server)
            self.rounds.remove(server)
        self.selection.remove_server(server)
        self.transport.disconnect(server)

    def stream(self, kind):
        return next(s for s in self.streams if s.kind.kind == kind)


def _fresh_random(purpose):
    return random.Random()
