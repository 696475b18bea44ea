"""The league (``make league``): the fleet profile beside the rules a user would pick instead
(core/selection/balancers.py), on every scenario at once. Root and TUN (testbed).

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
from server_select.core.selection.balancers import PEERS
from server_select.core.util.tables import markdown_table, median_range

NETWORK = ('paper_moving', 'crossing', 'near_equal', 'link_flap', 'loaded_server',
           'hung_server')
NETWORK_VARIANTS = ('oracle_fleet', 'fleet', 'fleet_hysteresis') + PEERS
# capacity cases: the capacity benchmark's scenario and what the league changes in it
CAPACITY = collections.OrderedDict([
    ('crowd', ['--scenario', 'crowd']),
    # the case: 6 robots, servers of 10, 15 and 20 % of a core, half to twice that
    ('overload_unequal', ['--scenario', 'overload', '--shares', '0.10,0.15,0.20']),
    ('herd', ['--scenario', 'herd']),
])
CAPACITY_VARIANTS = ('static', 'fleet', 'fleet_hysteresis') + PEERS


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
    from server_select.bench import capacity      # OpenCV and the messages: only here
    results = collections.OrderedDict()
    for case in args.cases:
        options = capacity.parse(CAPACITY[case] + ['--seconds', str(args.seconds)] +
                                 (['--loads', args.loads] if args.loads else []) +
                                 (['--capacity', 'image=%g' % args.image_capacity]
                                  if args.image_capacity else []))
        rows = results[case] = []
        work = os.path.join(args.out, 'capacity', case)
        options.frames = os.path.join(work, 'frames')
        capacity.write_frame(options.frames)
        options.cpu = capacity.cpu_per_task('image')
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


def _cell(values, spec, scale=1.0):
    known = [scale * v for v in values if v is not None]
    return median_range(known, spec) if known else '-'


NETWORK_COLUMNS = (('mean', 'mean ms', '%.1f', 1e3), ('p99', 'p99 ms', '%.0f', 1e3),
                   ('failed', 'failed', '%d', 1), ('switches_per_min', 'switches /min /robot',
                                                   '%.2f', 1),
                   ('reaction_mean', 'reaction s', '%.2f', 1),
                   ('extra_sends', 'extra sends %', '%.1f', 1),
                   ('samples_per_s', 'probes /s', '%.0f', 1), ('robot_cpu', 'robot CPU %',
                                                               '%.1f', 1))
CAPACITY_COLUMNS = (('goodput_share', 'goodput % of capacity', '%.0f', 100),
                    ('wanted', 'work still wanted %', '%.0f', 100),
                    ('failed', 'failed', '%d', 1), ('mean', 'mean ms', '%.0f', 1e3),
                    ('p99', 'p99 ms', '%.0f', 1e3),
                    ('switches', 'switches /min /robot', '%.1f', 1),
                    ('settled', 'settled switches', '%.1f', 1),
                    ('extra', 'extra sends %', '%.0f', 100))


def network_table(per_run):
    """One row per variant; mean and p99 also as a ratio to the oracle of the same run."""
    variants = [v for v in per_run[0]]
    rows = []
    for v in variants:
        runs = [r[v] for r in per_run if v in r]
        oracle = [r.get('oracle_fleet') for r in per_run if v in r]
        ratio = [f['mean'] / o['mean'] if o and o['mean'] and f['mean'] else None
                 for f, o in zip(runs, oracle)]
        cells = [_cell([f[k] for f in runs], spec, scale)
                 for k, _, spec, scale in NETWORK_COLUMNS]
        rows.append([v, len(runs)] + cells[:2] + [_cell(ratio, '%.3f')] + cells[2:])
    return markdown_table(['variant', 'runs', 'mean ms', 'p99 ms', 'mean / oracle'] +
                          [t for _, t, _, _ in NETWORK_COLUMNS[2:]], rows)


def capacity_table(rows):
    """One row per load and variant; goodput as a share of the servers' capacity."""
    groups = collections.OrderedDict()
    for row in sorted(rows, key=lambda r: (r['load'], CAPACITY_VARIANTS.index(r['variant'])
                                           if r['variant'] in CAPACITY_VARIANTS else 99)):
        row = dict(row, goodput_share=row['goodput'] / row['capacity'])
        groups.setdefault((row['load'], row['variant']), []).append(row)
    columns = [c for c in CAPACITY_COLUMNS
               if any(r.get(c[0]) is not None for g in groups.values() for r in g)]
    rows = [['%gx' % load, variant, len(group)] +
            [_cell([r.get(k) for r in group], spec, scale) for k, _, spec, scale in columns]
            for (load, variant), group in groups.items()]
    return markdown_table(['load', 'variant', 'runs'] + [t for _, t, _, _ in columns], rows)


def report(results, plot_path=None):
    text = ['# League', '', 'Each cell: median (min-max) over the runs. Failed tasks count '
            'at the task timeout in every mean and p99; switches and reactions from where '
            'tasks went.', '']
    for name, per_run in results.get('network', {}).items():
        if per_run:
            text += ['## %s (network)' % name, '', network_table(per_run), '']
    for case, rows in results.get('capacity', {}).items():
        if rows:
            text += ['## %s (capacity)' % case, '', capacity_table(rows), '']
    if plot_path:
        plot(results, plot_path)
        text += ['![league](%s)' % os.path.basename(plot_path), '']
    return '\n'.join(text)


def plot(results, path):
    """Mean round trip per network scenario (to the oracle) and goodput per capacity case
    at the highest load, one bar per variant (medians)."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    import statistics
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
    panels = ((axes[0], 'mean / oracle (network)', [
        (name, v, [r[v]['mean'] / r['oracle_fleet']['mean'] for r in per_run
                   if v in r and r[v]['mean'] and r.get('oracle_fleet')])
        for name, per_run in results.get('network', {}).items() for v in NETWORK_VARIANTS
        if v != 'oracle_fleet']),
        (axes[1], 'goodput / capacity at the highest load', [
            (case, v, [r['goodput'] / r['capacity'] for r in rows if r['variant'] == v and
                       r['load'] == max(x['load'] for x in rows)])
            for case, rows in results.get('capacity', {}).items()
            for v in CAPACITY_VARIANTS]))
    for ax, title, bars in panels:
        cases = list(collections.OrderedDict.fromkeys(b[0] for b in bars))
        variants = list(collections.OrderedDict.fromkeys(b[1] for b in bars))
        width = 0.8 / max(1, len(variants))
        for i, variant in enumerate(variants):
            values = [next((statistics.median(b[2]) for b in bars if b[0] == c and
                            b[1] == variant and b[2]), 0.0) for c in cases]
            ax.bar([x + i * width for x in range(len(cases))], values, width, label=variant)
        ax.set_xticks([x + 0.4 - width / 2 for x in range(len(cases))])
        ax.set_xticklabels(cases, rotation=20, fontsize=8)
        ax.set_title(title, fontsize=10)
    axes[0].axhline(1.0, color='k', lw=0.5)
    handles, labels = max((ax.get_legend_handles_labels() for ax in axes),
                          key=lambda hl: len(hl[1]))     # a part may be empty
    if labels:
        fig.legend(handles, labels, loc='lower center', ncol=len(labels), fontsize=8,
                   frameon=False)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(path, dpi=90)
    plt.close(fig)


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
