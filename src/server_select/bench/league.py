"""The league (``make league``): the fleet profile beside the rules a user would pick instead
(core/peers/balancers.py), on every scenario at once. Root and TUN (testbed).

Network scenarios (the suite's): every variant side by side in one run (shared servers and
links, robots of their own), ``--repeats`` runs each. Capacity scenarios (the capacity
benchmark's; a server's load is part of what is measured, so variants cannot share servers):
the variants in turn within each repeat. Switches and reactions come from where tasks went
(the server each task was first sent to), the same count for every variant: a peer's robots
choose per task, and their flags do not say what they did. Failed tasks count at the task
timeout in every mean and p99.

Writes ``league.json`` (every run's figures), ``league.md`` (the tables: median (min-max)
of the runs) and ``league.png`` into ``--out``.
"""

import collections
import json
import os
import sys

from server_select.bench import capacity_report, cli
from server_select.bench.league_report import (CAPACITY, CAPACITY_VARIANTS,
                                               NETWORK_VARIANTS, report)
from server_select.testbed.suite_scenario import NETWORK


def network(args, log):
    """``{scenario: [{variant: figures dict}]}``: every run of every network scenario."""
    from server_select.testbed.runner import guarded
    from server_select.testbed.suite import default_options, run_scenario
    from server_select.testbed.suite_report import load_runs, run_figures
    from server_select.testbed.suite_scenario import short_name
    out, results = os.path.join(args.out, 'network'), collections.OrderedDict()
    status = guarded('league', lambda: [
        run_scenario(name, out, repeat, args.variants, default_options(), log)
        for repeat in args.runs for name in args.scenarios])
    if status:
        raise SystemExit(status)
    for name in (short_name(s) for s in args.scenarios):   # every run in --out
        results[name] = [dict((v, f._asdict()) for v, f in
                              run_figures(meta, run, by_tasks=True).items())
                         for meta, run in load_runs(os.path.join(out, name))]
    return results


def capacity_runs(args, log):
    """``{case: [row]}``: the capacity benchmark's figures of each run (variant, load and
    repeat in each row)."""
    from server_select.bench import capacity, capacity_work   # OpenCV, messages: only here
    from server_select.vision import image_source
    results = collections.OrderedDict()
    for case in args.cases:
        options = capacity.parse(CAPACITY[case] + ['--seconds', str(args.seconds)] +
                                 (['--loads', args.loads] if args.loads else []) +
                                 (['--capacity', 'image=%g' % args.image_capacity]
                                  if args.image_capacity else []))
        rows = results[case] = []
        work = os.path.join(args.out, 'capacity', case)
        options.frames = os.path.join(work, 'frames')
        image_source.write_frame(options.frames)
        options.cpu = capacity_work.cpu_per_task('image')
        rate = options.capacity.get('image', sum(options.shares) / options.cpu)
        for repeat in args.runs:
            for load in options.loads:
                for variant in args.capacity_variants:
                    name = '%s-%g-%d' % (variant, load, repeat)
                    row = capacity.run_once(variant, 'image', load * rate / options.robots,
                                            options, work, name)
                    row.update(variant=variant, load=load, repeat=repeat, capacity=rate)
                    rows.append(row)
                    log('%s: %s' % (case, capacity_report.line(row)))
    return results


def parse(argv):
    parser = cli.parser(__doc__)
    parser.add_argument('--part', choices=('all', 'network', 'capacity'), default='all')
    parser.add_argument('--scenarios', default=','.join(NETWORK), help='network scenarios')
    parser.add_argument('--variants', default=','.join(NETWORK_VARIANTS),
                        help='network variants (suite names)')
    parser.add_argument('--cases', default=','.join(CAPACITY), help='capacity cases')
    parser.add_argument('--capacity-variants', default=','.join(CAPACITY_VARIANTS))
    parser.add_argument('--loads', help="capacity cases' offered loads, multiples of the "
                        "capacity (default: each case's own)")
    parser.add_argument('--repeats', type=int, default=3)
    parser.add_argument('--first-run', type=int, default=1, help='number the runs from this '
                        "one: more runs into an --out that has some (the report takes all)")
    parser.add_argument('--seconds', type=float, default=30.0,
                        help='measured s per capacity run')
    parser.add_argument('--image-capacity', type=float, default=None,
                        help="the servers' frames/s at load 1 (default: measured here)")
    parser.add_argument('--analyze-only', action='store_true',
                        help="do not run: re-write the report from --out's league.json")
    args = parser.parse_args(argv)
    for name in ('scenarios', 'variants', 'cases', 'capacity_variants'):
        setattr(args, name, [x for x in getattr(args, name).split(',') if x])
    bad = [c for c in args.cases if c not in CAPACITY]
    if bad or args.repeats < 1 or args.first_run < 1:
        parser.error('unknown capacity cases %s (of %s), or --repeats or --first-run < 1'
                     % (bad, ', '.join(CAPACITY)))
    args.runs = range(args.first_run, args.first_run + args.repeats)
    return args


def merge(old, new):
    """``new`` results over ``old`` (a league.json already in --out): network results are
    recomputed from every bag, so ``new``'s win; capacity rows of runs that ``new`` did not
    make are kept."""
    merged = dict(old, **new)
    for case, rows in old.get('capacity', {}).items():
        made = set((r['variant'], r['load'], r['repeat']) for r in
                   new.get('capacity', {}).get(case, []))
        merged.setdefault('capacity', {})[case] = [
            r for r in rows if (r['variant'], r['load'], r['repeat']) not in made] + \
            new.get('capacity', {}).get(case, [])
    return merged


def main(argv=None):
    args = parse(sys.argv[1:] if argv is None else argv)
    path = os.path.join(args.out, 'league.json')
    old = {}
    if os.path.exists(path):
        with open(path) as stream:
            old = json.load(stream)
    if args.analyze_only:
        results = old
    else:
        def log(text):
            print(text, file=sys.stderr, flush=True)
        results = {}
        if args.part in ('all', 'network'):
            results['network'] = network(args, log)
        if args.part in ('all', 'capacity'):
            results['capacity'] = capacity_runs(args, log)
        results = merge(old, results)
        cli.write(args.out, 'league.json', results)
    text = report(results, os.path.join(args.out, 'league.png'))
    cli.write(args.out, 'league.md', text)
    print(text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
