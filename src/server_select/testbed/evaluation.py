"""The paper's with/without-selection experiment on the testbed (no rospy).

Each mode runs the same scenario in a fresh testbed: roscore and the manager (or the
oracle) on the manager host, one server per server host, one robot per robot host, all
started with the package's own launch files inside the hosts' namespaces, and
``rosbag record`` on the manager host. Modes:

- ``select``: the system (manager + robots following its flag);
- ``fixed``: the paper's baseline, every robot pinned to one server (no manager runs);
- ``oracle``: robots follow the truly nearest server per the scenario file;
- ``fleet``: the system in the fleet profile (``profile:=fleet``: servers found at run
  time, each robot choosing per task), on the same scenario.

The bags (with a ``<bag>.json`` of run metadata beside each) are the only input of the
analysis (:mod:`server_select.testbed.bag_analysis`).
"""

import argparse
import copy
import json
import os
import sys

from server_select.core.settings import default
from server_select.testbed.linkemu import EmulatorError
from server_select.testbed.netns import Testbed
from server_select.testbed.runner import HostRun, RunOptions, at_once, guarded
from server_select.testbed.scenario import Scenario, ScenarioError

MODES = ('select', 'fixed', 'oracle', 'fleet')
PROFILE_OF_MODE = {'fleet': 'fleet'}     # a mode that is the system in another profile


def run_mode(scenario_path, mode, out_dir, options=None, log=print):
    """Run ``mode`` on the scenario; return the path of the recorded bag."""
    if mode not in MODES:
        raise ValueError('unknown mode %r, expected one of %s' % (mode, ', '.join(MODES)))
    options = copy.copy(options or RunOptions())
    if mode in PROFILE_OF_MODE:
        options.profile = PROFILE_OF_MODE[mode]
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
        run.start_nodes('select' if mode in PROFILE_OF_MODE else mode, options, bag)
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


def run_modes(scenario_path, modes, out_dir, options=None, side_by_side=False, log=print):
    """Run each of ``modes`` on the scenario; the paths of the bags, in their order.

    One after the other, or side by side: at once, each in a testbed of its own (a process
    each, with the namespace prefix ``<prefix>-<the mode's initial>``), the machine's load
    the same for all, in the time of one. Side by side the nodes start slower (on 2 cores,
    the first flag came 17 s into a 5-host scenario instead of 8 s: starting ROS nodes is
    CPU work), so the scenario's first events must come later."""
    options = options or RunOptions()
    if not side_by_side or len(modes) < 2:
        return [run_mode(scenario_path, mode, out_dir, options, log) for mode in modes]
    base = options.prefix or 'ssb%d' % os.getpid()
    calls = []
    for mode in modes:
        own = copy.copy(options)
        own.prefix = '%s-%s' % (base, mode[0])
        calls.append((run_mode, (scenario_path, mode, out_dir, own, log)))
    return at_once(calls)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if '--suite' in argv:       # the scenario suite (testbed/suite_cli.py)
        from server_select.testbed.suite_cli import main as suite_main
        return suite_main(argv)
    parser = argparse.ArgumentParser(
        description='Run the selection experiment on the testbed and analyse the bags.')
    parser.add_argument('--scenario', required=True, help='scenario YAML file')
    parser.add_argument('--modes', default='select,fixed,oracle',
                        help='comma-separated modes of %s (default: select,fixed,oracle)'
                        % ', '.join(MODES))
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
    parser.add_argument('--side-by-side', action='store_true',
                        help='run the modes at once, each in a testbed of its own (nodes '
                        'start slower: for scenarios whose first event is late)')
    args = parser.parse_args(argv)
    modes = [m for m in args.modes.split(',') if m]
    bad = [m for m in modes if m not in MODES]
    if bad or not modes:
        parser.error('unknown modes %s (expected %s)' % (bad, ', '.join(MODES)))
    try:
        out = os.path.join(args.out, Scenario.load(args.scenario).name)
    except ScenarioError as error:      # one line naming the file and what is wrong
        parser.error(str(error))
    options = RunOptions(fixed_server=args.fixed_server, window=args.window,
                         task_rate=args.task_rate, task_size=args.task_size,
                         hysteresis=args.hysteresis, profile=args.profile)
    status = guarded('evaluate', lambda: None if args.analyze_only else run_modes(
        args.scenario, modes, out, options, side_by_side=args.side_by_side))
    if status:
        return status
    from server_select.testbed import bag_analysis, bag_tables
    bag_analysis.analyze(out, modes)
    with open(os.path.join(out, 'summary.json')) as stream:
        summaries = json.load(stream)
    print('\n%s\n\n%s\n' % (bag_tables.table(summaries), bag_tables.legend(summaries)))
    print('report: %s (plots beside it: task_rtt.png, latency_<mode>.png)'
          % os.path.join(out, 'report.md'))
    print('\n'.join(bag_tables.verdicts(summaries)))
    return 0
