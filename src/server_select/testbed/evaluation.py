"""The paper's with/without-selection experiment on the testbed (no rospy).

Each mode runs the same scenario in a fresh testbed: roscore and the manager (or the
oracle) on the manager host, one server per server host, one robot per robot host, all
started with the package's own launch files inside the hosts' namespaces, and
``rosbag record`` on the manager host. Modes:

- ``select``: the system (manager + robots following its flag);
- ``fixed``: the paper's baseline, every robot pinned to one server (no manager runs);
- ``oracle``: robots follow the truly nearest server per the scenario file.

The bags (with a ``<bag>.json`` of run metadata beside each) are the only input of the
analysis (:mod:`server_select.testbed.bag_analysis`).
"""

import argparse
import json
import os
import signal
import sys
import threading

from server_select.core.settings import default
from server_select.core.procs import wait_until
from server_select.testbed.linkemu import EmulatorError
from server_select.testbed.scenario import Scenario, ScenarioError
from server_select.testbed.netns import Testbed

MODES = ('select', 'fixed', 'oracle')
MASTER_PORT = 11311
RECORDED = ('/(latency_R[0-9]+S[0-9]+|latency_samples|fleet_servers|server_select_flag|'
            '(server_[0-9]+/)?data|(robot_[0-9]+/)?processed_data|task_report)')


class RunOptions(object):
    """What a run does besides the scenario (the nodes' defaults reproduce the paper;
    ``window``, ``probe_rate`` and ``hysteresis`` None: the profile's)."""

    def __init__(self, fixed_server=1, window=None, task_rate=default('task_rate'),
                 task_size=default('task_size'), probe_rate=None,
                 probe_timeout=default('probe_timeout'), task_timeout=default('task_timeout'),
                 start_delay=5.0, hysteresis=None, prefix=None,
                 profile=default('profile')):
        self.fixed_server = fixed_server
        self.window = window
        self.task_rate = task_rate
        self.task_size = task_size
        self.probe_rate = probe_rate
        self.probe_timeout = probe_timeout
        self.task_timeout = task_timeout
        self.start_delay = start_delay
        self.hysteresis = hysteresis
        self.prefix = prefix
        self.profile = profile


def _given(options, *names):
    """Launch arguments of the ``options`` set (None: the profile's default)."""
    return ['%s:=%g' % (n, getattr(options, n)) for n in names
            if getattr(options, n) is not None]


def _ids(hosts):
    return ','.join(str(h.id) for h in sorted(hosts, key=lambda h: h.id))


class HostRun(object):
    """One mode of one scenario on an up testbed: environments and launches per host."""

    def __init__(self, tb, scenario, run_dir):
        self.tb = tb
        self.scenario = scenario
        self.run_dir = run_dir
        self.master = 'http://%s:%d' % (tb.address(scenario.manager.name), MASTER_PORT)

    def env(self, host):
        env = dict(os.environ, ROS_MASTER_URI=self.master, ROS_IP=self.tb.address(host),
                   ROS_HOME=os.path.join(self.run_dir, 'ros_home', host))
        env.pop('ROS_HOSTNAME', None)
        return env

    def popen(self, host, argv, log):
        return self.tb.popen(host, argv, env=self.env(host),
                             log=os.path.join(self.run_dir, '%s.log' % log))

    def launch(self, host, name, *args):
        return self.popen(host, ['roslaunch', '--wait', 'server_select', name] + list(args)
                          + ['output:=log'], host)

    def start_master(self):
        manager = self.scenario.manager.name
        self.popen(manager, ['roscore', '-p', str(MASTER_PORT)], 'roscore')
        up = wait_until(lambda: self.tb.run(manager, ['rostopic', 'list'], env=self.env(manager),
                                            timeout=10).returncode == 0, 30.0, period=0.3)
        if not up:
            raise EmulatorError('roscore on %s did not come up within 30 s' % manager)

    def start_nodes(self, mode, options, bag):
        scenario, manager = self.scenario, self.scenario.manager.name
        servers, robots = scenario.of_role('server'), scenario.of_role('robot')
        if mode == 'oracle':
            self.launch(manager, 'oracle.launch', 'scenario:=%s' % scenario.source,
                        't0:=%.6f' % self.tb.t0, 'robots:=%s' % _ids(robots))
        elif mode == 'select':   # fixed mode has no manager: no flag names an unused server
            fleet = options.profile == 'fleet'   # robots and servers learned at run time
            self.launch(manager, 'manager.launch', 'profile:=%s' % options.profile,
                        'robots:=%s' % ('[]' if fleet else _ids(robots)),
                        'servers:=%s' % ('[]' if fleet else _ids(servers)),
                        *_given(options, 'window', 'hysteresis'))
        self.popen(manager, ['rosbag', 'record', '--tcpnodelay', '-O', bag, '-e', RECORDED],
                   'rosbag')
        for server in servers:
            if server.start or server.stop is not None:
                threading.Thread(target=self.server_lifetime, args=(server, options),
                                 daemon=True).start()
            else:
                self.launch(server.name, 'server.launch', 'server_id:=%d' % server.id,
                            'profile:=%s' % options.profile)
        # fleet, select mode: every server found at run time (the manager lists them)
        learned = options.profile == 'fleet' and mode == 'select'
        for robot in robots:
            self.launch(robot.name, 'robot.launch', 'robot_id:=%d' % robot.id,
                        'profile:=%s' % options.profile,
                        'servers:=%s' % ('[]' if learned else _ids(servers)),
                        'mode:=%s' % ('fixed' if mode == 'fixed' else 'select'),
                        'fixed_server:=%d' % options.fixed_server,
                        'probe_timeout:=%g' % options.probe_timeout,
                        'task_rate:=%g' % options.task_rate, 'task_size:=%d' % options.task_size,
                        'task_timeout:=%g' % options.task_timeout,
                        'start_delay:=%g' % options.start_delay,
                        'manager_node:=%s' % ('/oracle' if mode == 'oracle' else '/manager'),
                        *_given(options, 'probe_rate'))

    def server_lifetime(self, server, options):
        """A server that starts late or stops early (the scenario's ``start`` / ``stop``):
        launched at its start, stopped with SIGINT (a clean shutdown) at its stop."""
        self.tb.sleep_until(server.start)
        proc = self.launch(server.name, 'server.launch', 'server_id:=%d' % server.id,
                           'profile:=%s' % options.profile)
        if server.stop is not None:
            self.tb.sleep_until(server.stop)
            proc.send_signal(signal.SIGINT)


def run_mode(scenario_path, mode, out_dir, options=None, log=print):
    """Run ``mode`` on the scenario; return the path of the recorded bag."""
    if mode not in MODES:
        raise ValueError('unknown mode %r, expected one of %s' % (mode, ', '.join(MODES)))
    options = options or RunOptions()
    scenario_path = os.path.abspath(scenario_path)
    scenario = Scenario.load(scenario_path)
    if mode == 'fixed' and options.fixed_server not in [s.id for s in scenario.of_role('server')]:
        raise ScenarioError('fixed server %d is not a server of %s'
                            % (options.fixed_server, scenario_path))
    run_dir = os.path.abspath(os.path.join(out_dir, mode))
    os.makedirs(run_dir, exist_ok=True)
    bag = os.path.join(out_dir, '%s.bag' % mode)
    if os.path.exists(bag):
        os.unlink(bag)
    with Testbed(scenario, scenario_path, run_dir, prefix=options.prefix) as tb:
        run = HostRun(tb, scenario, run_dir)
        run.start_master()
        run.start_nodes(mode, options, bag)
        log('%s: %s running until scenario time %.0f s (%s)'
            % (scenario.name, mode, scenario.duration, run_dir))
        tb.sleep_until(scenario.duration)
        meta = {'scenario': scenario_path, 'scenario_name': scenario.name,
                'mode': mode, 't0': tb.t0, 'duration': scenario.duration,
                'end': tb.scenario_time(), 'hosts': tb.hosts, 'options': vars(options)}
    with open(bag + '.json', 'w') as stream:
        json.dump(meta, stream, indent=1)
    if not os.path.exists(bag):
        raise EmulatorError('no bag was written for %s (see %s/rosbag.log)' % (mode, run_dir))
    return bag


def guarded(prog, work):
    """Run ``work()``; 0, or 2 (a testbed or scenario error, said on stderr) or 130
    (interrupted; the testbed was torn down on the way out)."""
    try:
        work()
    except (EmulatorError, ScenarioError) as error:
        print('%s: %s' % (prog, error), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print('%s: interrupted; the testbed was torn down' % prog, file=sys.stderr)
        return 130
    return 0


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if '--suite' in argv:       # the scenario suite (testbed/suite_cli.py)
        from server_select.testbed.suite_cli import main as suite_main
        return suite_main(argv)
    parser = argparse.ArgumentParser(
        description='Run the selection experiment on the testbed and analyse the bags.')
    parser.add_argument('--scenario', required=True, help='scenario YAML file')
    parser.add_argument('--modes', default='select,fixed,oracle',
                        help='comma-separated modes (default: select,fixed,oracle)')
    parser.add_argument('--out', default='results/eval', help='output folder')
    parser.add_argument('--fixed-server', type=int, default=1)
    parser.add_argument('--task-rate', type=float, default=default('task_rate'))
    parser.add_argument('--task-size', type=int, default=default('task_size'))
    parser.add_argument('--window', type=float, help="default: the profile's")
    parser.add_argument('--hysteresis', type=float, help="default: the profile's")
    parser.add_argument('--profile', choices=('paper', 'fleet'), default=default('profile'),
                        help='node defaults (default: paper, the paper as written)')
    parser.add_argument('--analyze-only', action='store_true',
                        help='do not run: analyse the bags already in --out')
    args = parser.parse_args(argv)
    modes = [m for m in args.modes.split(',') if m]
    bad = [m for m in modes if m not in MODES]
    if bad or not modes:
        parser.error('unknown modes %s (expected %s)' % (bad, ', '.join(MODES)))
    out = os.path.join(args.out, Scenario.load(args.scenario).name)
    options = RunOptions(fixed_server=args.fixed_server, window=args.window,
                         task_rate=args.task_rate, task_size=args.task_size,
                         hysteresis=args.hysteresis, profile=args.profile)
    status = guarded('evaluate', lambda: None if args.analyze_only else [
        run_mode(args.scenario, mode, out, options) for mode in modes])
    if status:
        return status
    from server_select.testbed import bag_analysis
    report = bag_analysis.analyze(out, modes)
    print(report)
    return 0
