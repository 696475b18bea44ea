"""One robot in two worlds: a scripted sequence of inputs (probe answers with their delays,
task results, a failed probe, a busy answer, a server leaving and one joining) given to
the robot through the node's wiring (RobotWire, the Prober's answer checks, each
TaskStream's result gate and pacing) and through the simulator's driver (SimRobot over a
scripted network) must yield the same probes, samples, moves, sends and task reports, in
the same order and at the same times.

Both run on one kind of virtual clock (the simulator's event loop); the node's threads are
stood in for by wake-ups at the times its ProbeLoop and Pacers would wake (after every
event, as they re-ask ``next_time``), and its rospy edges (service proxies, publishers,
the route's topics, the parameter server, the clock) by scripted fakes.
"""

import functools
import heapq
from unittest import mock

import pytest
import rospy

from server_select.core.load.work_queue import Load
from server_select.core.robot.robot import Robot
from server_select.core.robot.world import Events
from server_select.core.settings import default
from server_select.msg import SortResult
from server_select.ros import robot_parts
from server_select.ros.probe_loop import ProbeTimeout
from server_select.sim.events import EventLoop, Streams, Wakeup
from server_select.sim.robot import SimRobot
from server_select.sim.tasks import Kind
from server_select.srv import LatencyProbeResponse
from server_select.tasks.sort import Sort
from server_select.testbed.scenario import Host

ROBOT = 1
HALF_TRIP = {1: 0.0012, 2: 0.0004, 3: 0.0008, 4: 0.0003}     # one way, s
WORK = 0.004                 # each task's work at a server, s
SORT_SIZE, RATE = 20, 4.0
DOWN = (2, 3.0, 3.7)         # server 2 answers no probe and no task in [3.0, 3.7) s
BUSY = (2, 0.5)              # server 2's first task after 0.5 s is answered busy
LEAVES, JOINS = (3, 5.0), (4, 6.5)
UNTIL = 9.0


def params(name):
    """The fleet profile's parameters, the robot starting at once."""
    return {'mode': 'select', 'start_delay': 0.0, 'robot_id': ROBOT,
            'report_listeners': []}.get(name) if name in (
        'mode', 'start_delay', 'robot_id', 'report_listeners') else default(name, 'fleet')


class ThreadsLoop(EventLoop):
    """The event loop of the node's side: after every event, ``after_each()`` (the node's
    threads, its ProbeLoop and Pacers, ask when they next wake after every wake-up, answer
    and poke)."""
    after_each = None

    def run(self, until):
        heap = self._heap
        while heap and heap[0][0] <= until:
            when, _, callback, args = heapq.heappop(heap)
            self._now = when
            callback(*args)
            if self.after_each is not None:
                self.after_each()
        self._now = max(self._now, until)


class Script(object):
    """The world both robots live in: which server answers what, when, and how fast."""

    def __init__(self, loop):
        self.loop = loop
        self.busy_given = False

    def up(self, server, t):
        server_down, start, end = DOWN
        return not (server == server_down and start <= t < end)

    def load(self):
        return Load(0, 0, 1, 0.0, {'sort': WORK}, 0.0, {'sort': 0.0})

    def task_answer(self, server, t):
        """``(seconds until the robot has the answer, ok, busy)`` of a task sent to
        ``server`` at ``t``; None: no answer."""
        if not self.up(server, t):
            return None
        busy = server == BUSY[0] and t >= BUSY[1] and not self.busy_given
        self.busy_given = self.busy_given or busy
        return 2 * HALF_TRIP[server] + (0.0 if busy else WORK), not busy, busy


class Recorder(Events):
    """Logs what the robot tells, with the time, then hands it on to the driver's own."""

    def __init__(self, inner, log, clock):
        self.inner, self.log, self.clock = inner, log, clock

    def _note(self, *entry):
        self.log.append((round(self.clock(), 6),) + entry)

    def round(self, number, servers):
        self._note('round', number, tuple(servers))
        self.inner.round(number, servers)

    def sample(self, server, seq, rtt, error, wait, round_number):
        self._note('sample', server, seq, None if rtt is None else round(rtt, 6), error)
        self.inner.sample(server, seq, rtt, error, wait, round_number)

    def moved(self, server, why, kind):
        self._note('moved', server, why, kind)
        self.inner.moved(server, why, kind)

    def ejected(self, server, ejection, why):
        self._note('ejected', server, ejection.seconds, why)
        self.inner.ejected(server, ejection, why)

    def started(self, kind):
        self._note('started', kind)
        self.inner.started(kind)

    def report(self, outcome):
        self._note('report', outcome.task_id, outcome.server_id, outcome.answered_by,
                   outcome.ok, outcome.error, outcome.attempts)
        self.inner.report(outcome)


class Tap(object):
    """Logs the robot's sends (probes and tasks) on their way to its transport."""

    def __init__(self, inner, log, clock):
        self.inner, self.log, self.clock = inner, log, clock

    def __getattr__(self, name):
        return getattr(self.inner, name)

    def probe(self, server, seq, kinds, rates):
        self.log.append((round(self.clock(), 6), 'probe', server, seq,
                         tuple(round(r, 6) for r in rates)))
        return self.inner.probe(server, seq, kinds, rates)

    def send_task(self, kind, request, server, budget):
        self.log.append((round(self.clock(), 6), 'send', kind, request_id(request), server,
                         None if budget is None else round(budget, 6)))
        return self.inner.send_task(kind, request, server, budget)


def request_id(request):
    return request.task_id


def tap(robot, log):
    robot.events = Recorder(robot.events, log, robot.clock)
    robot.transport = Tap(robot.transport, log, robot.clock)


def membership(loop, robot, join, leave, poke):
    loop.at(LEAVES[1], lambda: (leave(LEAVES[0]), poke()))
    loop.at(JOINS[1], lambda: (join(JOINS[0]), poke()))


# -- the simulator's side ---------------------------------------------------------------
class _Connection(object):
    closed, usable_from = False, 0.0

    def __init__(self, delay):
        self.delay = delay

    def send(self, now, size):
        return now + self.delay

    def stalled(self, now):
        return False


class _SimWorld(object):
    """What SimRobot asks of a simulation: the script's loop, network and servers."""

    def __init__(self, script):
        self.script, self.loop = script, script.loop
        self.streams = Streams(1)
        self.model = mock.Mock(alone=lambda kind, rng, size: WORK, shared_delay=lambda rng: 0.0)
        self.network = mock.Mock(once=lambda a, b, t, size, tag: t + HALF_TRIP[_id(a, b)],
                                 connection=lambda a, b, tag: _Connection(
                                     HALF_TRIP[_id(a, b)]))
        self.servers = dict((s, _SimServer(self, s)) for s in HALF_TRIP)

    def report(self, robot, outcome):
        pass

    def work_answered(self, robot, wanted):
        pass

    def probe_answered(self, robot, server, rtt):
        pass


def _id(a, b):
    return int((b if a == 'robot' else a)[len('server'):])


class _SimServer(object):
    def __init__(self, world, server):
        self.world, self.id = world, server
        self.host = mock.Mock()
        self.host.name = 'server%d' % server

    def probe_done(self, t):     # down: answered after the robot gave up
        return t if self.world.script.up(self.id, t - HALF_TRIP[self.id]) else t + 60.0

    def probe(self, robot, rates):
        return self.world.script.load()

    def submit(self, task, budget, reply):
        loop = self.world.loop
        answer = self.world.script.task_answer(self.id, loop.now() - HALF_TRIP[self.id])
        if answer is not None:       # the result's transfer back is the connection's
            delay, ok, busy = answer
            loop.at(loop.now() + delay - 2 * HALF_TRIP[self.id], reply, task, ok,
                    '' if ok else 'busy', busy)


def simulated(log):
    script = Script(EventLoop())
    world = _SimWorld(script)
    host = Host('robot', 'robot', ROBOT, 0.0, None)     # a scenario's robot, up throughout
    with mock.patch('server_select.sim.robot.Robot', functools.partial(_tapped_robot, log)):
        robot = SimRobot(world, host, [1, 2, 3], params, [Kind('sort', RATE, False, 80,
                                                               SORT_SIZE)])
    membership(script.loop, robot.robot, robot.join, robot.leave, lambda: None)
    script.loop.at(0.0, robot.start)
    script.loop.run(UNTIL)


def _tapped_robot(log, *args, **kwargs):
    robot = Robot(*args, **kwargs)
    tap(robot, log)
    return robot


# -- the node's side --------------------------------------------------------------------
class _Publisher(object):
    def __init__(self, *args, **kwargs):
        pass

    def publish(self, msg):
        pass

    def unregister(self):
        pass


class _Proxy(object):
    uri = 'rosrpc://localhost:1'

    def __init__(self, name, *args):
        self.resolved_name = name
        self.server = int(name.rsplit('_S', 1)[-1].lstrip('S'))

    def connected(self):
        return True

    def close(self):
        pass

    def reconnect(self):
        pass


class _ProbeLoop(object):
    """The Prober's loop: a request answered (or timed out) on the script's clock."""

    def __init__(self, script, *args, **kwargs):
        self.script = script

    def start_probe(self, proxy, request, timeout, then):
        loop, server, sent = self.script.loop, proxy.server, self.script.loop.now()
        state = {'done': False}

        def end(response, rtt, error):
            if not state['done']:
                state['done'] = True
                then(response, rtt, error)
        if self.script.up(server, sent):
            rtt = 2 * HALF_TRIP[server]
            load = self.script.load()
            loop.at(sent + rtt, end, LatencyProbeResponse(
                server_id=server, seq=request.seq, stamp=request.stamp, queued=load.queued,
                in_service=load.in_service, workers=load.workers, backlog=load.backlog,
                kinds=['sort'], service_time=[WORK], service_error=[0.0],
                utilization=load.utilization), (sent + rtt) - sent, None)
        loop.at(sent + timeout, end, None, None, ProbeTimeout('no answer within %.3g s'
                                                              % timeout))

    def poke(self):
        pass


class _Route(object):
    """A stream's topics: each task answered as the script says."""
    script = None

    def __init__(self, robot_id, kind, on_result):
        self.on_result = on_result

    def start(self):
        pass

    def add(self, server):
        pass

    def remove(self, server):
        pass

    def heard(self, server, node=None):
        return []

    def publishers(self):
        return []

    def wired(self, server, node=None):
        return True

    def publish(self, request, server):
        loop = self.script.loop
        answer = self.script.task_answer(server, loop.now())
        if answer is None:
            return
        delay, ok, busy = answer
        result = SortResult(robot_id=request.robot_id, task_id=request.task_id,
                            server_id=server, ok=ok, error='' if ok else 'busy', busy=busy,
                            data=sorted(request.data))
        result._connection_header = {'callerid': '/server%d' % server}
        loop.at(loop.now() + delay, self.on_result, result)


def on_the_node(log):
    script = Script(ThreadsLoop())
    loop = script.loop
    _Route.script = script
    patches = [mock.patch('server_select.ros.robot_parts.param', params),
               mock.patch('server_select.ros.node._FLEET_NS', '/'),
               mock.patch('server_select.ros.seal._configured', lambda: (None, None)),
               mock.patch('server_select.ros.prober.keyed', lambda: False),
               mock.patch('server_select.ros.prober.TimedServiceProxy', _Proxy),
               mock.patch('server_select.ros.prober.ProbeLoop',
                          functools.partial(_ProbeLoop, script)),
               mock.patch('server_select.ros.probe_samples.SealedPublisher', _Publisher),
               mock.patch('server_select.ros.task_stream.SealedPublisher', _Publisher),
               mock.patch.dict(robot_parts.ROUTES, {'direct': _Route}),
               mock.patch('rospy.Time.now', lambda: rospy.Time.from_sec(loop.now()))]
    for patch in patches:
        patch.start()
    try:
        wire = robot_parts.RobotWire(ROBOT, lambda server, refresh=False: '/server%d' % server,
                                     True)
        robot = Robot(ROBOT, [1, 2, 3], 'select', params,
                      [(Sort(ROBOT, {'size': SORT_SIZE, 'seed': 1}), RATE)], transport=wire,
                      events=wire, clock=loop.now, stamp=rospy.Time.now,
                      random=_random_as_simulated)
        wire.attach(robot)
        tap(robot, log)
        streams = list(wire.streams.values())
        wakes = [Wakeup(loop, wire.prober.on_round)] + [Wakeup(loop, s._act) for s in streams]
        times = [robot.next_probe_time] + [s.core.next_time for s in streams]

        def poke():     # what the node's threads do after every event: ask again
            for wake, when in zip(wakes, times):
                wake.request(when())
        membership(loop, robot, robot.add_server, robot.remove_server, poke)

        def start():
            for stream in streams:
                stream.start()
            robot.start()
            wire.prober.robot = robot
            loop.after_each = poke
        loop.at(0.0, start)
        loop.run(UNTIL)
    finally:
        for patch in reversed(patches):
            patch.stop()


def _random_as_simulated(purpose):
    """The random sources the simulator gives (its seed 1), so that both robots draw the
    same stream phase and the same rule draws."""
    streams = Streams(1)
    return streams.rng('rule', ROBOT) if purpose == 'rule' else \
        streams.rng('tasks', ROBOT, purpose.partition('/')[2])


@pytest.fixture(scope='module')
def both():
    node, sim = [], []
    on_the_node(node)
    simulated(sim)
    return node, sim


def test_the_script_exercises_every_input(both):
    node, _ = both
    kinds = set(entry[1] for entry in node)
    assert {'probe', 'sample', 'send', 'report', 'moved', 'round', 'started'} <= kinds
    assert any(e[1] == 'sample' and e[2] == DOWN[0] and e[4] for e in node)   # failed probe
    assert any(e[1] == 'report' and e[3] == LEAVES[0] for e in node)
    assert any(e[1] == 'probe' and e[2] == JOINS[0] for e in node)
    assert any(e[1] == 'send' and e[4] == JOINS[0] for e in node)      # the joined one used
    assert not any(e[1] == 'probe' and e[2] == LEAVES[0] and e[0] > LEAVES[1] for e in node)
    assert sum(1 for e in node if e[1] == 'report') > 25


def test_the_node_and_the_simulator_decide_the_same(both):
    node, sim = both
    first = next((i for i, (a, b) in enumerate(zip(node, sim)) if a != b), None)
    assert first is None and len(node) == len(sim), (
        'first difference at %s:\nnode: %s\nsim:  %s' % (
            first, node[first - 2:first + 3] if first is not None else node[len(sim):][:3],
            sim[first - 2:first + 3] if first is not None else sim[len(node):][:3]))
