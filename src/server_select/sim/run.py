"""One simulated run: a scenario, one or more variants, one seed (no rospy).

Variants are the scenario suite's (``testbed/suite.py``: a mode, a profile, parameters)
and ``static`` (every robot fixed to its server of the best static assignment). Each
variant's robots are the scenario's robots with the variant's parameters. By default a
run simulates one variant alone on the scenario's servers (:func:`simulate`), and the
league runs each variant with the same seed: paired runs. ``together`` runs every variant
side by side on shared servers, as the testbed's suite does (its calibration).

A scenario file's ``suite: robot_args`` say what the robots send (``task_rate``,
``task_size``, ``sort_tasks``, ``frame_rate`` with ``image_source`` or ``image_topic``,
``task_timeout``, ``start_delay``), as they do on the testbed, and ``suite: host_args``
what one robot sends otherwise (``{robot7: {frame_rate: 4}}``: a burst robot's own rate,
beside a ``stop``); ``suite: measure_from``
where the measured part starts (35 s, the suite's, by default); ``suite: hop_ms`` the
middleware's delay per message where it is not the model's (a bag's run on one host);
``suite: check_every`` the servers' checks of an idle kind (the fleet profile's: 0.5 s).
"""

import collections

from server_select.core.rule.least_latency import MECHANISMS
from server_select.core.settings import PARAMS, default
from server_select.sim.events import EventLoop, Streams
from server_select.sim.network import Network
from server_select.sim.robot import SimRobot
from server_select.sim.server import SimServer
from server_select.sim.tasks import Kind
from server_select.testbed.suite import MEASURE_FROM, VARIANTS, Variant
from server_select.testbed.suite_scenario import REPLICA, server_args

STATIC = Variant('fixed', 'paper', {})
SORT_BYTES_PER_VALUE = 4
KEPT_RTTS = 256          # probe round trips kept per pair (a minute of a contender's, at 4 Hz)
FRAME_BYTES = 40000          # a 640x480 JPEG frame at quality 80, and its annotated answer

Record = collections.namedtuple('Record', 'robot variant ended outcome')


def variant(name):
    """The Variant a name means: a suite variant, ``static``, or either with parameters
    of its robots changed, ``fleet:hedge=false:contender_rate=0``, or mechanisms of its
    rule switched off, ``fleet~keep~robust`` (ablations; a ValueError names an unknown
    variant or parameter; :func:`rule_args` the rule's)."""
    base, _, changes = name.split('~')[0].partition(':')
    if base != 'static' and base not in VARIANTS:
        raise ValueError('unknown variant %r (expected static or one of %s)'
                         % (base, ', '.join(VARIANTS)))
    spec = STATIC if base == 'static' else VARIANTS[base]
    rule_args(name)
    params = dict(spec.params)
    for change in [c for c in changes.split(':') if c]:
        key, _, value = change.partition('=')
        if key not in PARAMS or not value:
            raise ValueError('%s: %r is not a robot parameter=value' % (name, change))
        params[key] = PARAMS[key].parse(key, value)
    return spec._replace(params=params)


def rule_args(name):
    """The per-task rule's own arguments a variant's name asks for (None: none; a
    ValueError names a mechanism the fleet's rule does not have)."""
    off = name.split('~')[1:]
    unknown = sorted(set(off) - set(MECHANISMS))
    if unknown:
        raise ValueError('%s: no mechanism %s (the rule has %s)'
                         % (name, ', '.join(unknown), ', '.join(MECHANISMS)))
    return {'off': off} if off else None


def measured_window(scenario):
    """``(measure_from, [warnings])`` of ``scenario``: the measured part starts at its
    ``suite: measure_from`` (ValueError when that leaves no time before its end); a
    warning names each change that falls before it (the figures do not see it)."""
    start = float(scenario.suite.get('measure_from', MEASURE_FROM))
    if start >= scenario.duration:
        raise ValueError('%s: nothing is measured: suite: measure_from (%g s) is not before '
                         'the end of its duration (%g s); lower measure_from or lengthen '
                         'duration' % (scenario.source, start, scenario.duration))
    changes = [('link %s-%s' % pair, at) for pair, link in sorted(scenario.links.items())
               for at in link.times if at > 0]
    for host in scenario.hosts.values():
        changes += [('%s starts' % host.name, host.start)] if host.start > 0 else []
        changes += [('%s stops' % host.name, host.stop)] if host.stop is not None else []
        changes += [('%s hangs' % host.name, a) for a, _ in host.hang]
        changes += [('%s work changes' % host.name, at) for at, _ in host.work]
    return start, ['%s: %s at %g s is before the measured part (from %g s): the figures do '
                   'not see it' % (scenario.source, what, at, start)
                   for what, at in sorted(changes, key=lambda c: c[1]) if at < start]


def kinds_of(args):
    """The task streams that a scenario's ``robot_args`` ask for (robot.launch's names)."""
    kinds = []
    if str(args.get('sort_tasks', True)).lower() not in ('false', '0'):
        size = int(args.get('task_size', default('task_size')))
        kinds.append(Kind('sort', float(args.get('task_rate', default('task_rate'))), False,
                          SORT_BYTES_PER_VALUE * size, size))
    if args.get('image_source') or args.get('image_topic'):
        kinds.append(Kind('image', float(args.get('frame_rate', default('frame_rate'))), True,
                          FRAME_BYTES, 0))
    return kinds


class Simulation(object):
    """The loop, network, servers and robots of one run."""

    def __init__(self, scenario, model, seed, variants, fixed=None, together=False,
                 groups=None):
        self.scenario, self.model, self.seed = scenario, model, seed
        self.loop = EventLoop()
        self.streams = Streams(seed)
        # a scenario may say its middleware's delay (a bag's run on one host: less)
        self.network = Network(scenario, self.streams, float(
            scenario.suite['hop_ms']) * 1e-3 if 'hop_ms' in scenario.suite else model.hop)
        check_every = server_args(scenario.suite)['check_every']
        self.servers = dict((h.id, SimServer(self.loop, h, model, self.streams, check_every))
                            for h in scenario.of_role('server'))
        suite = scenario.suite
        args = dict(suite.get('robot_args') or {})
        self.measure_from = measured_window(scenario)[0]
        self.timeout = float(args.get('task_timeout', default('task_timeout')))
        by_host = suite.get('host_args') or {}
        strays = sorted(set(by_host) - set(h.name for h in scenario.of_role('robot')))
        if strays:
            raise ValueError('%s: suite: host_args names no robot of it: %s'
                             % (scenario.source, ', '.join(strays)))
        self.records, self.robots = [], []
        self.answers = collections.defaultdict(collections.Counter)   # variant -> wanted?
        # (robot, server) -> its answered probes' newest round trips (the node's samples)
        self.probe_rtts = collections.defaultdict(lambda: collections.deque(maxlen=KEPT_RTTS))
        self.variant_of = {}
        for index, name in enumerate(variants, start=1):
            spec = variant(name)
            params = dict(spec.params, mode='select' if spec.mode == 'oracle' else spec.mode)
            params.update((k, v) for k, v in args.items()
                          if k in ('task_timeout', 'start_delay'))
            get = _getter(params, spec.profile)
            for host in scenario.of_role('robot'):
                rid = REPLICA * index + host.id if together else host.id
                self.variant_of[rid] = name
                servers = groups[host.id] if groups else sorted(self.servers)
                kinds = kinds_of(dict(args, **by_host.get(host.name, {})))
                robot = SimRobot(self, host._replace(id=rid), servers, get,
                                 kinds, fixed=(fixed or {}).get(host.id),
                                 oracle=spec.mode == 'oracle', scenario_id=host.id,
                                 rule_args=rule_args(name))
                self.robots.append(robot)

    def report(self, robot, outcome):
        self.records.append(Record(robot, self.variant_of[robot], self.loop.now(), outcome))

    def probe_answered(self, robot, server, rtt):
        self.probe_rtts[(robot, server)].append(rtt)

    def work_answered(self, robot, wanted):
        """A server's finished task reached ``robot``: still wanted, or not."""
        self.answers[self.variant_of[robot]][wanted] += 1

    def completed_work(self):
        """Tasks a second the servers finished in the measured part."""
        done = sum(1 for server in self.servers.values() for t in server.completions
                   if t >= self.measure_from)
        return done / (self.scenario.duration - self.measure_from)

    def run(self):
        for robot in self.robots:     # nodes come up within the first two seconds
            start = robot.host.start + self.streams.rng('start', robot.scenario_id).uniform(
                0.0, 2.0)
            self.loop.at(start, robot.start)
        self.loop.run(self.scenario.duration)
        return self


def _getter(params, profile):
    return lambda name: params[name] if name in params else default(name, profile)


def simulate(scenario, model, seed, variants, fixed=None, together=False, groups=None):
    """The finished :class:`Simulation` of ``variants`` on ``scenario`` with ``seed``
    (``fixed``: {robot: server} of fixed mode; ``groups``: {robot: its servers}, a grouped
    fleet's, where tasks go and what it probes; None: every server)."""
    return Simulation(scenario, model, seed, variants, fixed, together, groups).run()
