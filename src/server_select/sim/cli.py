"""``rosrun server_select simulate SCENARIO.yaml --variants fleet,prequal --seeds 30``: one
scenario in the simulator, each variant with the same seeds, the table printed and
``league.json``, ``league.md`` and ``league.png`` written to ``--out``.

``--from-bag run.bag`` takes the links from a recorded run instead (each robot-server
pair's probe round trips: :mod:`server_select.sim.from_bag`) and writes that scenario
beside the results: what the other rules would have done on the run's links.
"""

import argparse
import os
import sys

import yaml

from server_select.core.settings import default

from server_select.sim import cells, league, report
from server_select.sim.model import Model
from server_select.sim.report import ORACLE
from server_select.sim.run import measured_window
from server_select.testbed.scenario import ScenarioError
from server_select.testbed.suite_scenario import short_name


VARIANTS = ('fleet', 'prequal', 'p2c_peak_ewma')


def parse(argv):
    parser = argparse.ArgumentParser(prog='simulate', description=__doc__.split('\n\n')[0])
    parser.add_argument('scenario', nargs='?', help='a scenario file (the testbed\'s '
                        'format), a suite scenario\'s name, or gen:<seed>')
    parser.add_argument('--from-bag', metavar='BAG', help='the links of a recorded run')
    parser.add_argument('--variants', help='suite variants (the oracle is always run; '
                        'default: %s, and with --from-bag the bag\'s own profile first)'
                        % ','.join(VARIANTS))
    parser.add_argument('--seeds', type=int, default=30)
    parser.add_argument('--first-seed', type=int, default=1)
    parser.add_argument('--together', action='store_true', help='the variants side by side '
                        'on shared servers, as the testbed runs them (one run per seed)')
    cells.add_arguments(parser)
    parser.add_argument('--out', default='simulation',
                        help='folder for the tables (default: simulation, here)')
    args = parser.parse_args(argv)
    if bool(args.scenario) == bool(args.from_bag):
        parser.error('give a scenario or --from-bag, one of them')
    return args


def _from_bag(path, out):
    """The scenario of the run recorded in the bag at ``path``, written to ``out`` (its
    path), and the run's own figures."""
    from server_select.sim import from_bag
    from server_select.testbed.bag_analysis import load
    run = load(path)
    data = from_bag.scenario(run, Model.load())
    profile = own_profile(run)
    data['suite']['check_every'] = default('check_every', profile)   # its servers'
    name = os.path.abspath(os.path.join(out, 'from_bag.yaml'))
    with open(name, 'w') as stream:
        stream.write('# the run of %s\n' % path)
        yaml.safe_dump(data, stream, sort_keys=False)
    return name, from_bag.recorded(run, data['suite']['measure_from']), profile


def own_profile(run):
    """The profile a recorded run's robots had: the fleet's managers publish their server
    list (``fleet_servers``), the paper's do not."""
    return 'fleet' if run.servers else 'paper'


def _beside(own, variants, seeds):
    """The bag's own figures beside each simulated variant's (median [95 % interval])."""
    def figures(mean, failed, tasks):
        return '%s ms, %s failed of %s tasks' % (mean, failed, tasks)
    lines = ['this run (the bag): %s, %.2f switches /min /robot' % (figures(
        '-' if own['mean'] is None else '%.2f' % (1e3 * own['mean']), own['failed'],
        own['tasks']), own['switches'])]
    for variant, runs in variants.items():
        series = [runs[s] for s in seeds if s in runs]
        lines.append('simulated %s: %s' % (variant, figures(
            report.cell([r.get('mean') for r in series], '%.2f', 1e3),
            report.cell([r.get('failed') for r in series], '%.0f'),
            report.cell([r.get('tasks') for r in series], '%.0f'))))
    return '\n'.join(lines)


def main(argv=None):
    args = parse(sys.argv[1:] if argv is None else argv)
    os.makedirs(args.out, exist_ok=True)
    name, profile = args.scenario, None
    try:
        if args.from_bag:
            name, own, profile = _from_bag(args.from_bag, args.out)
        # a bad file or an empty measured part: its one line, before any run
        for warning in measured_window(league.network_scenario(name))[1]:
            print('simulate: warning: %s' % warning, file=sys.stderr)
    except (ScenarioError, ValueError, OSError) as error:
        print('simulate: %s' % error, file=sys.stderr)
        return 2
    asked = args.variants.split(',') if args.variants else \
        [profile] * (profile is not None) + list(VARIANTS)
    variants = [ORACLE] + [v for v in dict.fromkeys(asked) if v and v != ORACLE]
    options = league.parse(['--seeds', str(args.seeds), '--first-seed', str(args.first_seed),
                            '--scenarios', name, '--variants', ','.join(variants),
                            '--cases', '', '--processes', str(args.processes),
                            '--out', args.out] + (['--together'] if args.together else []) +
                           (['--scheduler', args.scheduler] if args.scheduler else []))
    results, _ = league.run(options, lambda text: print(text, file=sys.stderr))
    results.update(seeds=options.seeds, variants={'network': variants},
                   scenarios={'network': [short_name(name)]})
    print(report.write(results, args.out))
    if args.from_bag:
        print(_beside(own, results['network'][short_name(name)], options.seeds))
    print('written: %s' % os.path.join(args.out, 'league.md'))
    return 0


if __name__ == '__main__':
    sys.exit(main())
