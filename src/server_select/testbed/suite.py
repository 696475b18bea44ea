"""The scenario suite: every way of selecting a server, side by side, on each scenario.

One run of a scenario gives each *variant* (a mode, a profile and parameters: the paper's
baseline pinned to one server, the oracle, the paper's rule, the fleet profile, each
policy alone, the fleet profile with hedged tasks) its own copy of every robot: robot
``r`` of variant ``k`` is robot ``10 k + r`` on a host of its own with the same links as
the scenario's robot ``r``. The servers (launched with ``suite_scenario.server_args``) and
the network are shared, so all variants meet the same changes at the same moment; each
select variant has a manager of its own (``manager_<variant>``). Runs are repeated, each
in a fresh testbed with its own namespace prefix.

The bags (``<out>/<scenario>/run<i>.bag``, a ``.json`` beside each) are ``suite_report``'s input.
"""

import collections
import json
import os
import signal
import threading

import yaml

from server_select.core.peers.balancers import PEERS
from server_select.core.util.procs import stat_fields
from server_select.testbed.runner import RECORDED, HostRun, RunOptions, host_ids
from server_select.testbed.linkemu import EmulatorError
from server_select.testbed.netns import Testbed
from server_select.testbed.traces import netns_pids
from server_select.testbed.scenario import Scenario, ScenarioError
from server_select.testbed.suite_scenario import (expand, launch_args, robot_params,
                                                  scenario_path, scenario_robot_args,
                                                  server_args, short_name)

Variant = collections.namedtuple('Variant', 'mode profile params host')
Variant.__new__.__defaults__ = ({},)     # host: what its robots' hosts are like (scenario keys)
PI3_BUSY = {'like': 'pi3', 'busy': 0.5}  # a Raspberry Pi 3 robot half busy with its own work
# the per-task rules: the fleet's own (least_latency) and the league's peers
RULES = ('least_latency',) + PEERS
# the fleet profile's robots following the oracle's flags: a rule that chooses per task
# (the profile's least_latency) keeps flags for the record only
FOLLOW_FLAGS = {'policy': 'mean'}
# the fleet profile's selection before it chose per task with least_latency (for the league)
# (less its draws for moves, ~spread, which went with it)
PREVIOUS_FLEET = {'policy': 'hysteresis', 'hysteresis': 0.0003, 'margin_z': 3.0, 'dwell': 3.0,
                  'passive': True, 'task_memory': 5.0}


def peer_params(name):
    """The parameters of the league's peer ``name`` (core/peers/balancers.py): the fleet profile
    with that rule choosing per task, every server probed alike (Prequal's pool wants
    answers from all; adaptive probing follows the fleet's own ranking), replication
    without hedges (it already sends each task twice)."""
    if name == 'least_latency':     # the fleet's own rule: the fleet's adaptive probing
        return {'policy': name}
    params = {'policy': name, 'contender_rate': 0}
    if name == 'replicate':
        params['hedge'] = False
    return params


# What the suite compares. Parameters go to the variant's manager and robots (each takes
# the ones its launch file has).
VARIANTS = collections.OrderedDict([
    ('fixed', Variant('fixed', 'paper', {})),
    ('oracle', Variant('oracle', 'paper', {})),
    ('oracle_fleet', Variant('oracle', 'fleet', FOLLOW_FLAGS)),
    ('paper', Variant('select', 'paper', {})),
    ('fleet', Variant('select', 'fleet', {})),
    ('hysteresis', Variant('select', 'paper', dict(policy='hysteresis', hysteresis=0.0005,
                                                   margin_z=2.5, dwell=5.0))),
    ('fleet_no_hedge', Variant('select', 'fleet', {'hedge': False})),
    ('fleet_uniform', Variant('select', 'fleet', {'contender_rate': 0})),
    # not in the default run: ask for them with --variants
    ('fleet_2hz', Variant('select', 'fleet', {'contender_rate': 0, 'probe_rate': 2.0,
                                              'window': 2.0})),
    ('fleet_window1', Variant('select', 'fleet', {'window': 1.0})),
    ('fleet_20hz', Variant('select', 'fleet', {'contender_rate': 20.0,
                                               'contender_budget': 40.0})),
    # Prequal's 3 probes per query at the suite's 2 tasks a second: contenders share 6 Hz
    ('fleet_6hz', Variant('select', 'fleet', {'contender_budget': 6.0})),
    # the fleet profile's rule before least_latency: the manager's hysteresis over the robots'
    # windows, answered tasks as samples
    ('fleet_hysteresis', Variant('select', 'fleet', PREVIOUS_FLEET)),
    # every probe sample to the manager, which ranks (the robots' own rankings: fleet)
    ('fleet_samples', Variant('select', 'fleet', {'sample_stream': 'robot'})),
    # robots on emulated Raspberry Pi 3 hosts, 50 % busy with their own work (each
    # compared with the oracle on the same hosts)
    ('oracle_pi3_busy', Variant('oracle', 'paper', {}, PI3_BUSY)),
    ('oracle_fleet_pi3_busy', Variant('oracle', 'fleet', FOLLOW_FLAGS, PI3_BUSY)),
    ('paper_pi3_busy', Variant('select', 'paper', {}, PI3_BUSY)),
    ('fleet_pi3_busy', Variant('select', 'fleet', {}, PI3_BUSY)),
] + [(name, Variant('select', 'fleet', peer_params(name))) for name in RULES])
ON_REQUEST = ('fleet_2hz', 'fleet_window1', 'fleet_20hz', 'fleet_6hz', 'fleet_samples',
              'fleet_hysteresis', 'oracle_pi3_busy', 'oracle_fleet_pi3_busy', 'paper_pi3_busy',
              'fleet_pi3_busy') + RULES
DEFAULT_VARIANTS = tuple(v for v in VARIANTS if v not in ON_REQUEST)
SCENARIOS = ('paper_moving', 'crossing', 'near_equal', 'link_flap', 'loaded_server',
             'hung_server', 'search_sweep')
MEASURE_FROM = 35.0  # s of scenario time: nodes are up, every variant sends tasks
SUITE_RECORDED = RECORDED[:-1] + '|task_samples)'


def _args(params, accepted):
    return ['%s:=%s' % (k, str(v).lower() if isinstance(v, bool) else v)
            for k, v in sorted(params.items()) if k in accepted]


class SuiteRun(HostRun):
    """One run of one scenario with every variant side by side."""

    def start_variants(self, variants, owners, options, bag, robot_args=None, servers=None):
        manager = self.scenario.manager.name
        robots_of = collections.defaultdict(list)
        for rid, (variant, _) in sorted(owners.items()):
            robots_of[variant].append(rid)
        manager_args, robot_args_of = launch_args('manager.launch'), launch_args('robot.launch')
        self.record(bag, '-e', SUITE_RECORDED)
        for name in variants:
            variant, ids = VARIANTS[name], ','.join(str(r) for r in robots_of[name])
            if variant.mode == 'select':
                self.launch(manager, 'manager.launch', 'name:=manager_%s' % name,
                            'profile:=%s' % variant.profile, 'robots:=%s' % ids,
                            'servers:=%s' % ('[]' if variant.profile == 'fleet' else
                                             host_ids(self.scenario.of_role('server'))),
                            *_args(variant.params, manager_args))
        for server in self.scenario.of_role('server'):
            self.launch(server.name, 'server.launch', 'server_id:=%d' % server.id,
                        'routing:=direct',      # takes broadcast and direct tasks
                        'test_knobs:=true',     # its events may set ~work_delay
                        *_args(servers or server_args(), ('check_every',)))
            threading.Thread(target=self.server_events, args=(server,), daemon=True).start()
        if robot_args and self.tb.t0 is None:
            raise ScenarioError('%s: a sweep starts at time zero, which its robots must be '
                                'told: time_zero: launch' % self.scenario.source)
        extra = scenario_robot_args(robot_args, self.tb.t0)
        for robot in self.scenario.of_role('robot'):
            name, original = owners[robot.id]
            args = dict(extra, robot_index=original - 1) if extra else {}
            self.start_robot(robot, name, VARIANTS[name], options, robot_args_of, args)
        for name in (n for n in variants if VARIANTS[n].mode == 'oracle'):
            self.launch(manager, 'oracle.launch', 'scenario:=%s' % self.scenario.source,
                        't0:=%.6f' % self.start_clock(), 'name:=%s' % name,
                        'robots:=%s' % ','.join(str(r) for r in robots_of[name]),
                        'profile:=%s' % VARIANTS[name].profile)
        self.start_clock()

    def start_robot(self, robot, name, variant, options, accepted, extra):
        learned = variant.profile == 'fleet' and variant.mode == 'select'
        params = robot_params(variant.params, options, extra)
        self.launch(robot.name, 'robot.launch', 'robot_id:=%d' % robot.id,
                    'profile:=%s' % variant.profile,
                    'servers:=%s' % ('[]' if learned else
                                     host_ids(self.scenario.of_role('server'))),
                    'mode:=%s' % ('fixed' if variant.mode == 'fixed' else 'select'),
                    'fixed_server:=%d' % options.fixed_server,
                    'manager_node:=/%s' % (name if variant.mode == 'oracle' else
                                           'manager_' + name),
                    *_args(params, accepted), stage=0)

    def robot_cpu(self):
        """``{robot id: CPU %}``: user + system time of each robot node over its life."""
        tick, out = os.sysconf('SC_CLK_TCK'), {}
        with open('/proc/uptime') as stream:
            uptime = float(stream.read().split()[0])
        for host in self.scenario.of_role('robot'):
            for pid in netns_pids(self.tb.hosts[host.name]['netns']):
                try:
                    fields = stat_fields('/proc/%d/stat' % pid)
                    with open('/proc/%d/cmdline' % pid) as stream:
                        command = stream.read()
                except OSError:
                    continue
                if '__name:=robot' in command:
                    life = max(1e-9, uptime - int(fields[19]) / float(tick))
                    out[str(host.id)] = 100.0 * (int(fields[11]) + int(fields[12])) / tick / life
        return out

    def server_events(self, server):
        """The scenario's hang and work times of ``server``, as they come (each one logged
        in ``events.log`` of the run)."""
        events = [(a, 'stop') for a, _ in server.hang] + [(b, 'cont') for _, b in server.hang]
        events += [(at, delay) for at, delay in server.work]
        for at, what in sorted(events, key=lambda e: e[0]):
            self.tb.sleep_until(at)
            if what in ('stop', 'cont'):
                sig = signal.SIGSTOP if what == 'stop' else signal.SIGCONT
                count = 0
                for pid in netns_pids(self.tb.hosts[server.name]['netns']):
                    try:
                        os.kill(pid, sig)
                        count += 1
                    except ProcessLookupError:
                        pass
                done = '%s to %d processes' % (sig.name, count)
            else:
                manager = self.scenario.manager.name
                proc = self.tb.run(manager, ['rosparam', 'set', '/server%d/work_delay'
                                             % server.id, repr(what)], env=self.env(manager))
                done = 'work_delay %g s (rosparam exit %d)' % (what, proc.returncode)
            with open(os.path.join(self.run_dir, 'events.log'), 'a') as log:
                log.write('%.3f %s: %s\n' % (self.tb.scenario_time(), server.name, done))


def run_scenario(name, out_dir, repeat, variants, options, log=print):
    """Run scenario ``name`` once with ``variants`` side by side; the bag's path."""
    path = scenario_path(name)
    name = short_name(name)
    try:
        with open(path) as stream:
            data = yaml.safe_load(stream)
        suite = data.pop('suite', None) or {}
        variants = [v for v in variants if v in suite.get('variants', variants)]
        data, owners = expand(data, variants, dict((v, VARIANTS[v].host) for v in variants))
    except (OSError, yaml.YAMLError, AttributeError, KeyError, TypeError) as error:
        raise ScenarioError('%s: not a scenario the suite can use (%s)' % (path, error))
    run_dir = os.path.abspath(os.path.join(out_dir, name, 'run%d' % repeat))
    os.makedirs(run_dir, exist_ok=True)
    path = os.path.join(run_dir, 'scenario.yaml')
    with open(path, 'w') as stream:
        yaml.safe_dump(data, stream)
    scenario = Scenario.load(path)
    bag = os.path.join(out_dir, name, 'run%d.bag' % repeat)
    if os.path.exists(bag):
        os.unlink(bag)
    with Testbed(scenario, path, run_dir, prefix=options.prefix) as tb:
        run = SuiteRun(tb, scenario, run_dir)
        run.start_master()
        run.start_variants(variants, owners, options, bag, suite.get('robot_args'),
                           server_args(suite))
        log('%s run %d: %d variants, %d robots, until %.0f s (%s)'
            % (name, repeat, len(variants), len(owners), scenario.duration, run_dir))
        tb.sleep_until(scenario.duration)
        meta = {'robot_cpu': run.robot_cpu(), 'scenario': path, 'scenario_name': name,
                'variants': list(variants),
                'owners': dict((str(k), v) for k, v in owners.items()), 't0': tb.t0,
                'duration': scenario.duration,
                'measure_from': float(suite.get('measure_from', MEASURE_FROM)),
                'options': dict(vars(options), **dict(     # as the robots ran them
                    (k, v) for k, v in (suite.get('robot_args') or {}).items()
                    if k in vars(options)))}
    with open(bag + '.json', 'w') as stream:
        json.dump(meta, stream, indent=1)
    if not os.path.exists(bag):
        raise EmulatorError('no bag was written for %s (see %s/rosbag.log)' % (name, run_dir))
    return bag


def default_options():
    """The suite's run options: the nodes' defaults; tasks start 10 s after a robot."""
    return RunOptions(start_delay=10.0)
