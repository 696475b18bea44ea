"""A simulated robot (no rospy): the robot node's parts, built from its parameters by the
constructors the node uses (selection with its rule, health, probe plan, load view, a
task flow per kind, one retry budget), wired to the simulated network.

What the node's threads do is done here by events, in the same order: a probe round when
the plan says (a server whose probe is still out is skipped, and failed once it is late),
each answer as a sample to the selection, the health table and the load view; a task
every period once a server is usable, the flow ticked at its next wake, a held-back send
made when a task ends.
"""

import functools
import itertools

from server_select.core.flow.budget import RetryBudget
from server_select.core.load.robot_load import RobotLoad
from server_select.core.selection import probing
from server_select.core.selection.answer_time import STILL_OUT, AnswerTimes
from server_select.core.selection.robot_parts import robot_selection
from server_select.core.selection.rank import NO_SERVER
from server_select.sim.events import Wakeup
from server_select.sim.stream import TaskStream

PROBE_BYTES = 120          # a LatencyProbe request or answer


class _Probe(object):
    __slots__ = ('server', 'sent', 'done')

    def __init__(self, server, sent):
        self.server, self.sent, self.done = server, sent, False


class SimRobot(object):
    """Robot ``host`` (a scenario Host) of simulation ``sim`` (its loop, network, servers,
    streams, model and records), with parameters ``get(name)`` and ``kinds``."""

    def __init__(self, sim, host, servers, get, kinds, fixed=None, oracle=False,
                 scenario_id=None, rule_args=None):
        self.sim, self.host, self.id = sim, host, host.id
        # the scenario's robot this one is (its links, its oracle; its random streams:
        # side by side, every variant's copy meets the same tasks)
        self.scenario_id = host.id if scenario_id is None else scenario_id
        self.loop = sim.loop
        clock = self.loop.now
        self.selection, self.health, self.policy = robot_selection(
            self.id, servers, get('mode'), fixed, get, clock=clock,
            rng=sim.streams.rng('rule', self.id), rule_args=rule_args)
        self.balancer = self.selection.balancer
        self.plan = probing.from_params(get)
        self.probe_timeout = get('probe_timeout')
        self.answer_times = AnswerTimes()
        self.load = RobotLoad(dict((k.name, k.rate) for k in kinds), self.selection.heading,
                              self.balancer, clock, max_age=get('window')) \
            if get('load_aware') and get('mode') == 'select' else None
        self.budget = RetryBudget(get('retry_budget'), clock=clock)
        self.start_delay = get('start_delay')
        ids = itertools.count(1)
        self.streams = [TaskStream(self, kind, get, ids) for kind in kinds]
        self.oracle = oracle
        self.answered = set()
        self._out = {}                 # server -> its probe still out
        self.probes = 0
        self._round = Wakeup(self.loop, self._probe_round)
        self._first = self._last_round = 0.0
        self._to, self._from = {}, {}  # server -> connection for tasks, for results
        self._flagged = None

    # -- start ----------------------------------------------------------------------------
    def start(self):
        now = self.loop.now()
        for server in self.selection.servers:
            self.plan.add(server, now)
        self._first = now + self.plan.tick       # the node's first round: one tick on
        self._ready_at = now + self.start_delay
        self._round.request(self._next_round())
        for stream in self.streams:
            stream.start(now)
        if self.oracle:
            self._oracle_flag()

    def ready(self):
        return self.loop.now() >= self._ready_at and self.selection.ready(self.answered)

    # -- the oracle's flags (20 Hz, each change; the oracle node's update rate) -------------
    def _oracle_flag(self):
        now = self.loop.now()
        ranked, _ = self.sim.scenario.ranking(self.scenario_id, now)
        servers = [s for _, s in ranked]
        if servers != self._flagged or int(now) != int(now - 0.05):
            self._flagged = servers
            self.selection.on_flag(self.id, servers[0] if servers else NO_SERVER, servers)
        self.loop.after(0.05, self._oracle_flag)

    # -- probes (as ros/prober.py's round) ------------------------------------------------
    def _next_round(self):
        due = self.plan.next_time()
        return None if due is None else max(due, self._first, self._last_round + 0.001)

    def _still_out(self, server, now):
        probe = self._out.get(server)
        if probe is None or probe.done:
            return False
        return True if now is None else not self.answer_times.late(server, now - probe.sent)

    def _probe_round(self):
        now = self._last_round = self.loop.now()
        if self.plan.adaptive:
            self.plan.update(self.selection.contenders(), now, self.selection.task_rate())
        for server in [s for s in self.plan.due(now) if not self._still_out(s, now)]:
            if self._still_out(server, None):      # and late: a failed sample
                self._sample(server, None, STILL_OUT, None)
            else:
                self._probe(server, now)
        self._round.request(self._next_round())

    def _probe(self, server_id, now):
        probe = self._out[server_id] = _Probe(server_id, now)
        self.probes += 1
        server = self.sim.servers[server_id]
        kinds, rates = self.load.announcement(server_id) if self.load else ((), ())
        network, here, there = self.sim.network, self.host.name, server.host.name

        def at_server():
            t = self.loop.now()
            done = server.probe_done(t)
            if done is None:            # no process there: the connection is refused
                self.loop.at(network.once(there, here, t, PROBE_BYTES, 'probe'),
                             self._probe_end, probe, None, 'connection refused')
            else:
                self.loop.at(done, answer)

        def answer():
            load = server.probe(self.id, list(zip(kinds, rates)))
            self.loop.at(network.once(there, here, self.loop.now(), PROBE_BYTES, 'probe'),
                         self._probe_end, probe, load, None)
        self.loop.at(network.once(here, there, now, PROBE_BYTES, 'probe'), at_server)
        self.loop.at(now + self.probe_timeout, self._probe_end, probe, None,
                     'no answer within %.3g s' % self.probe_timeout)

    def _probe_end(self, probe, load, error):
        if probe.done:
            return
        probe.done = True
        if error is not None:
            self._sample(probe.server, None, error, None)
            return
        rtt = self.loop.now() - probe.sent
        self.answered.add(probe.server)
        self.answer_times.answered(probe.server, rtt)
        wait = self.load.on_answer(probe.server, load, rtt) if self.load else None
        self._sample(probe.server, rtt, '', wait)

    def _sample(self, server, rtt, error, wait):
        """A probe sample, as the node's ``on_sample`` and the prober's re-check take it."""
        ok = not error
        try:
            self.selection.on_sample(server, ok, rtt + wait if ok and wait else rtt,
                                     wait=wait if ok else None)
        except ValueError:
            pass
        if not ok:
            self.on_failure(server, 'probe failed: %s' % error, probe=True,
                            late=error == STILL_OUT)
            return
        self.health.probe_ok(server)
        self._heard(server)
        if self.balancer is not None and self.load is None:
            self.balancer.probed(server, rtt)

    # -- evidence from tasks (as the node's) ----------------------------------------------
    def on_failure(self, server, why, probe=False, late=False):
        self.health.failure(server, why, probe, late)

    def on_busy(self, kind, server):
        expected = self.load.expected(kind)(server) if self.load is not None else None
        self.health.busy(server, max(1.0, expected or 0.0))

    # -- task traffic ---------------------------------------------------------------------
    def _heard(self, server_id):
        """A good probe: a task connection to the server stalled in TCP's back-off is made
        anew (the node's ``TaskStream.heard``); the server connects again after a round
        trip to the master and one to the robot, and what is sent before reaches nobody."""
        connection = self._to.get(server_id)
        now = self.loop.now()
        if connection is not None and connection.stalled(now):
            connection.close()
            self._to[server_id] = self._connect(server_id, now + 2.0 * (
                self.loop.now() - self._out[server_id].sent))

    def _connect(self, server_id, usable_from):
        connection = self.sim.network.connection(self.host.name,
                                                 self.sim.servers[server_id].host.name, 'task')
        connection.usable_from = usable_from
        return connection

    def send(self, task, server_id, budget, stream):
        server = self.sim.servers[server_id]
        connection = self._to.get(server_id)
        if connection is None:
            connection = self._to[server_id] = self._connect(server_id, 0.0)
        now = self.loop.now()
        if now < connection.usable_from:
            return                        # no subscriber connected yet: rospy drops it
        arrival = connection.send(now, task.bytes)
        self.loop.at(arrival, self._arrive, connection, server, task, budget, stream)

    def _arrive(self, connection, server, task, budget, stream):
        if not connection.closed:
            server.submit(task, budget, functools.partial(self._reply, server, stream))

    def _reply(self, server, stream, task, ok, error, busy):
        connection = self._from.get(server.id)
        if connection is None:
            connection = self._from[server.id] = self.sim.network.connection(
                server.host.name, self.host.name, 'result')
        arrival = connection.send(self.loop.now(), task.bytes if ok else PROBE_BYTES)
        self.loop.at(arrival, stream.resolve, task, server.id, ok, error, busy)
