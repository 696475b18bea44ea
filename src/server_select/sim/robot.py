"""A simulated robot: the package's own :class:`~server_select.core.robot.robot.Robot`,
driven on the simulation's virtual clock. This module holds no robot logic: it is the
robot's transport over the modelled network (probes, tasks and results as transfers,
TCP's stalled connections renewed as the node renews them) and its wake-ups, as the
node's threads are (one for probe rounds, one per task stream)."""

import functools

from server_select.core.flow.task_flow import ENDED
from server_select.core.robot.robot import Robot
from server_select.core.robot.world import Events, Transport
from server_select.sim.events import Wakeup
from server_select.sim.oracle import OracleFlags
from server_select.sim.tasks import PROBE_BYTES, TaskKind


class SimRobot(Transport, Events):
    """Robot ``host`` (a scenario Host) of simulation ``sim`` (its loop, network, servers,
    random streams, model and records), with parameters ``get(name)`` and ``kinds``;
    ``scenario_id``: the scenario's robot it is (its links, its oracle, its random streams:
    side by side, every variant's copy meets the same tasks)."""

    def __init__(self, sim, host, servers, get, kinds, fixed=None, oracle=False,
                 scenario_id=None, rule_args=None):
        self.sim, self.host, self.id, self.loop = sim, host, host.id, sim.loop
        self.scenario_id, self.oracle = host.id if scenario_id is None else scenario_id, oracle
        task_kinds = [(TaskKind(k, self.id, sim.model, self._random('tasks/' + k.name)),
                       k.rate) for k in kinds]
        self.robot = Robot(self.id, servers, get('mode'), get, task_kinds, transport=self,
                           events=self, clock=self.loop.now,
                           random=self._random, fixed=fixed, rule_args=rule_args)
        self.streams = self.robot.streams
        self._round = Wakeup(self.loop, self._probe_round)
        self._wakes = [Wakeup(self.loop, functools.partial(self._act, s)) for s in self.streams]
        self._to, self._from = {}, {}  # server -> connection for tasks, for results

    def _random(self, purpose):
        """The run's seeded stream for the rule's draws, or a kind's tasks."""
        rng = self.sim.streams.rng
        return rng('rule', self.id) if purpose == 'rule' else \
            rng('tasks', self.scenario_id, purpose.partition('/')[2])

    def start(self):
        self.robot.start()
        self._round.request(self.robot.next_probe_time())
        for stream, wake in zip(self.streams, self._wakes):
            wake.request(stream.next_time())
        if self.oracle:
            OracleFlags(self.loop, self.sim.scenario, self.scenario_id, self.robot).start()

    def join(self, server_id):
        """Server ``server_id`` joined the fleet (as membership tells the node)."""
        self.robot.add_server(server_id)
        self._round.request(self.robot.next_probe_time())

    def leave(self, server_id):
        """Server ``server_id`` left the fleet."""
        self.robot.remove_server(server_id)

    # -- the robot's wake-ups -------------------------------------------------------------
    def _stopped(self):      # past its host's stop: no probe, no task sent
        return self.host.stop is not None and self.loop.now() >= self.host.stop

    def _probe_round(self):
        if self._stopped():
            return
        self.robot.probe_round()
        self._round.request(self.robot.next_probe_time())

    def _act(self, stream):
        if self._stopped():
            return
        stream.act()
        self._wakes[self.streams.index(stream)].request(stream.next_time())

    def report(self, outcome):
        self.sim.report(self.id, outcome)

    def sample(self, server, seq, rtt, error, wait, round_number):
        if rtt is not None and not error:
            self.sim.probe_answered(self.id, server, rtt)

    # -- the transport: probes ------------------------------------------------------------
    def probe(self, server_id, seq, kinds, rates):
        server, now = self.sim.servers[server_id], self.loop.now()
        network, here, there = self.sim.network, self.host.name, server.host.name
        robot = self.robot

        def back(t, then, *args):
            self.loop.at(network.once(there, here, t, PROBE_BYTES, 'probe'), then, *args)

        def at_server():
            done = server.probe_done(self.loop.now())
            if done is None:            # no process there: the connection is refused
                back(self.loop.now(), robot.probe_failed, server_id, seq, 'connection refused')
            else:
                self.loop.at(done, answer)

        def answer():
            load = server.probe(self.id, list(zip(kinds, rates)))
            back(self.loop.now(), lambda: robot.probe_answered(
                server_id, seq, self.loop.now() - now, load))
        self.loop.at(network.once(here, there, now, PROBE_BYTES, 'probe'), at_server)
        self.loop.after(robot.probe_timeout, robot.probe_failed, server_id, seq,
                        'no answer within %.3g s' % robot.probe_timeout)

    def heard(self, server_id, rtt):
        """A task connection stalled in TCP's back-off is made anew, as the node's is; the
        server connects again after a round trip to the master and one to the robot, and
        what is sent before reaches nobody."""
        connection, now = self._to.get(server_id), self.loop.now()
        if connection is not None and connection.stalled(now):
            connection.close()
            self._connection(self.sim.servers[server_id], 'task', now + 2.0 * rtt)

    # -- the transport: tasks and results -------------------------------------------------
    def _connection(self, server, tag, usable_from=None):
        """``server``'s ``tag`` connection, 'task' (``_to`` it) or 'result' (``_from`` it),
        made at its first use or, ``usable_from`` given, anew (what was sent is dropped)."""
        table = self._to if tag == 'task' else self._from
        if usable_from is not None or server.id not in table:
            here, there = self.host.name, server.host.name
            table[server.id] = self.sim.network.connection(
                *((here, there) if tag == 'task' else (there, here)), tag=tag)
            table[server.id].usable_from = usable_from or 0.0
        return table[server.id]

    def send_task(self, kind, task, server_id, budget):
        server, now = self.sim.servers[server_id], self.loop.now()
        connection = self._connection(server, 'task')
        if now < connection.usable_from:
            return                        # no subscriber connected yet: rospy drops it
        arrival = connection.send(now, task.bytes)
        self.loop.at(arrival, self._arrive, connection, server, task, budget or 0.0)

    def _arrive(self, connection, server, task, budget):
        if not connection.closed:
            server.submit(task, budget, functools.partial(self._reply, server))

    def _reply(self, server, task, ok, error, busy):
        connection = self._connection(server, 'result')
        arrival = connection.send(self.loop.now(), task.bytes if ok else PROBE_BYTES)
        self.loop.at(arrival, self._resolve, task, server.id, ok, error, busy)

    def _resolve(self, task, server_id, ok, error, busy):
        stream = self.robot.stream(task.kind)
        resolution = stream.resolve(task.task_id, server_id, ok, error, None, busy)
        if ok:
            self.sim.work_answered(self.id, resolution.status == ENDED)
        self._wakes[self.streams.index(stream)].request(stream.next_time())
