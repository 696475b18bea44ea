"""The paper's with/without-selection experiment on the testbed (no rospy).

Each mode runs the same scenario in a fresh testbed: roscore and the manager (or the
oracle) on the manager host, one server per server host, one robot per robot host, all
started with the package's own launch files inside the hosts' namespaces, and
``rosbag record`` on the manager host. Modes:

- ``select``: the system (manager + robots following its flag);
- ``fixed``: the paper's baseline, every robot pinned to one server;
- ``oracle``: robots follow the truly nearest server per the scenario file.

The bags (with a ``<bag>.json`` of run metadata beside each) are the only input of the
analysis (:mod:`server_select.bag_analysis`).
"""

import argparse
import json
import os
import sys
import time

from server_select.linkemu import EmulatorError
from server_select.scenario import Scenario, ScenarioError
from server_select.testbed import Testbed

MODES = ('select', 'fixed', 'oracle')
MASTER_PORT = 11311
RECORDED = '/(latency_R[0-9]+S[0-9]+|server_select_flag|data|processed_data|task_report)'


class RunOptions(object):
    """What a run does besides the scenario (defaults reproduce the paper)."""

    def __init__(self, fixed_server=1, window=5.0, task_rate=2.0, task_size=1000,
                 probe_rate=1.0, probe_timeout=0.5, task_timeout=2.0, start_delay=5.0,
                 hysteresis=0.0, prefix='ssb'):
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


def _ids(hosts):
    return ','.join(str(h.id) for h in sorted(hosts, key=lambda h: h.id))


def _wait_for_master(tb, host, env, timeout=30.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if tb.run(host, ['rostopic', 'list'], env=env, timeout=10).returncode == 0:
            return
        time.sleep(0.3)
    raise EmulatorError('roscore on %s did not come up within %.0f s' % (host, timeout))


def run_mode(scenario_path, mode, out_dir, options=None, log=print):
    """Run ``mode`` on the scenario; return the path of the recorded bag."""
    if mode not in MODES:
        raise ValueError('unknown mode %r, expected one of %s' % (mode, ', '.join(MODES)))
    options = options or RunOptions()
    scenario = Scenario.load(scenario_path)
    servers, robots = scenario.of_role('server'), scenario.of_role('robot')
    if mode == 'fixed' and options.fixed_server not in [s.id for s in servers]:
        raise ScenarioError('fixed server %d is not a server of %s'
                            % (options.fixed_server, scenario_path))
    run_dir = os.path.abspath(os.path.join(out_dir, mode))
    os.makedirs(run_dir, exist_ok=True)
    bag = os.path.join(out_dir, '%s.bag' % mode)
    if os.path.exists(bag):
        os.unlink(bag)
    with Testbed(scenario, scenario_path, run_dir, prefix=options.prefix) as tb:
        manager = scenario.manager.name
        master = 'http://%s:%d' % (tb.address(manager), MASTER_PORT)

        def env(host):
            e = dict(os.environ, ROS_MASTER_URI=master, ROS_IP=tb.address(host),
                     ROS_HOME=os.path.join(run_dir, 'ros_home', host))
            e.pop('ROS_HOSTNAME', None)
            return e

        def launch(host, name, *args):
            return tb.popen(host, ['roslaunch', '--wait', 'server_select', name] + list(args)
                            + ['output:=log'], env=env(host),
                            log=os.path.join(run_dir, '%s.log' % host))

        tb.popen(manager, ['roscore', '-p', str(MASTER_PORT)], env=env(manager),
                 log=os.path.join(run_dir, 'roscore.log'))
        _wait_for_master(tb, manager, env(manager))
        if mode == 'oracle':
            launch(manager, 'oracle.launch', 'scenario:=%s' % os.path.abspath(scenario_path),
                   't0:=%.6f' % tb.t0, 'robots:=%s' % _ids(robots))
        else:
            launch(manager, 'manager.launch', 'robots:=%s' % _ids(robots),
                   'servers:=%s' % _ids(servers), 'window:=%g' % options.window,
                   'hysteresis:=%g' % options.hysteresis)
        tb.popen(manager, ['rosbag', 'record', '--tcpnodelay', '-O', bag, '-e', RECORDED],
                 env=env(manager), log=os.path.join(run_dir, 'rosbag.log'))
        for server in servers:
            launch(server.name, 'server.launch', 'server_id:=%d' % server.id)
        for robot in robots:
            launch(robot.name, 'robot.launch', 'robot_id:=%d' % robot.id,
                   'servers:=%s' % _ids(servers),
                   'mode:=%s' % ('fixed' if mode == 'fixed' else 'select'),
                   'fixed_server:=%d' % options.fixed_server,
                   'probe_rate:=%g' % options.probe_rate,
                   'probe_timeout:=%g' % options.probe_timeout,
                   'task_rate:=%g' % options.task_rate, 'task_size:=%d' % options.task_size,
                   'task_timeout:=%g' % options.task_timeout,
                   'start_delay:=%g' % options.start_delay)
        log('%s: %s running until scenario time %.0f s (%s)'
            % (scenario.name, mode, scenario.duration, run_dir))
        tb.wait_until(scenario.duration)
        t_end = tb.scenario_time()
        meta = {'scenario': os.path.abspath(scenario_path), 'scenario_name': scenario.name,
                'mode': mode, 't0': tb.t0, 'duration': scenario.duration, 'end': t_end,
                'hosts': tb.hosts, 'options': vars(options)}
    with open(bag + '.json', 'w') as stream:
        json.dump(meta, stream, indent=1)
    if not os.path.exists(bag):
        raise EmulatorError('no bag was written for %s (see %s/rosbag.log)' % (mode, run_dir))
    return bag


def main(argv=None):
    parser = argparse.ArgumentParser(
        description='Run the selection experiment on the testbed and analyse the bags.')
    parser.add_argument('--scenario', required=True, help='scenario YAML file')
    parser.add_argument('--modes', default='select,fixed,oracle',
                        help='comma-separated modes (default: select,fixed,oracle)')
    parser.add_argument('--out', default='results/eval', help='output folder')
    parser.add_argument('--fixed-server', type=int, default=1)
    parser.add_argument('--task-rate', type=float, default=2.0)
    parser.add_argument('--task-size', type=int, default=1000)
    parser.add_argument('--window', type=float, default=5.0)
    parser.add_argument('--hysteresis', type=float, default=0.0)
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
                         hysteresis=args.hysteresis)
    try:
        if not args.analyze_only:
            for mode in modes:
                run_mode(args.scenario, mode, out, options)
    except (EmulatorError, ScenarioError) as error:
        print('evaluate: %s' % error, file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print('evaluate: interrupted; the testbed was torn down', file=sys.stderr)
        return 130
    from server_select import bag_analysis
    report = bag_analysis.analyze(out, modes)
    print(report)
    return 0
