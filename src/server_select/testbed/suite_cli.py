"""``scripts/evaluate --suite`` (``make evaluate-suite``): run the scenario suite and write
its report (``<out>/report.md``, ``summary.json``, plots per scenario run)."""

import argparse
import collections
import os
import sys

from server_select.testbed.runner import guarded
from server_select.testbed.scenario import Scenario
from server_select.testbed.suite import (DEFAULT_VARIANTS, MEASURE_FROM, SCENARIOS, VARIANTS,
                                         default_options, run_scenario)
from server_select.testbed.suite_scenario import short_name
from server_select.testbed import suite_report


def parse(argv):
    parser = argparse.ArgumentParser(
        prog='evaluate --suite',
        description='Run every variant side by side on each scenario of the suite, '
                    'repeatedly, and compare them (docs/evaluation.md, "The scenario suite").')
    parser.add_argument('--suite', action='store_true', help=argparse.SUPPRESS)
    parser.add_argument('--scenarios', default=','.join(SCENARIOS),
                        help='comma-separated names, or scenario files (.yaml) '
                             '(default: %(default)s)')
    parser.add_argument('--variants', default=','.join(DEFAULT_VARIANTS),
                        help='comma-separated, of %s (default: %%(default)s)'
                        % ', '.join(VARIANTS))
    parser.add_argument('--repeats', type=int, default=3, help='runs per scenario (3)')
    parser.add_argument('--out', default='results/suite', help='output folder')
    parser.add_argument('--analyze-only', action='store_true',
                        help='do not run: analyse the bags already in --out')
    args = parser.parse_args(argv)
    args.scenarios = [s for s in args.scenarios.split(',') if s]
    args.variants = [v for v in args.variants.split(',') if v]
    bad = [s for s in args.scenarios if s not in SCENARIOS and not (
        s.endswith('.yaml') and os.path.isfile(s))] + \
        [v for v in args.variants if v not in VARIANTS]
    oracle = [v for v in args.variants if VARIANTS[v].mode == 'oracle'] if not bad else []
    if bad or not args.scenarios or not oracle or args.repeats < 1:
        parser.error('unknown scenarios or variants %s, or no oracle (ratios are to the '
                     'oracle), or --repeats < 1' % bad)
    return args


def report(args):
    """Analyse the bags in ``args.out``; write and return the report text."""
    from server_select.testbed.bag_analysis import oracle_changes
    from server_select.testbed.suite_plots import plot_cdf, plot_time
    results, text = collections.OrderedDict(), []
    for name in (short_name(s) for s in args.scenarios):
        folder = os.path.join(args.out, name)
        runs = suite_report.load_runs(folder)
        if not runs:
            continue
        results[name] = [suite_report.run_figures(meta, run) for meta, run in runs]
        text += ['## %s (%d runs)' % (name, len(runs)), '',
                 suite_report.scenario_table(results[name]), '']
        for index, (meta, run) in enumerate(runs, start=1):
            owners = dict((int(k), tuple(v)) for k, v in meta['owners'].items())
            scenario = Scenario.load(meta['scenario'])
            firsts = dict((robot, rid) for rid, (_, robot) in sorted(owners.items(),
                                                                     reverse=True))
            changes = [(t, owners[r][1], s) for t, r, s in oracle_changes(
                scenario, sorted(firsts.values()), meta['measure_from'], meta['duration'])]
            timeout = meta['options']['task_timeout']
            plot_time(run, owners, changes, timeout,
                      os.path.join(folder, 'time_run%d.png' % index), '%s run %d' % (name, index))
            plot_cdf(run, owners, timeout, meta['measure_from'],
                     os.path.join(folder, 'cdf_run%d.png' % index), '%s run %d' % (name, index))
            text.append('![%s run %d](%s/time_run%d.png) ![cdf](%s/cdf_run%d.png)'
                        % (name, index, name, index, name, index))
        text.append('')
    if not results:
        raise FileNotFoundError('no suite bags in %s' % args.out)
    head = ['# Scenario suite', '', 'Each cell: median of the runs (min-max). Round trips '
            'from `task_report` after %.0f s of scenario time, a failed task counted at '
            'the task timeout; ratios to the oracle of the same run and task routing.'
            % MEASURE_FROM, '',
            '## Summary: mean / oracle, p99 / oracle, failed tasks (medians)', '',
            suite_report.summary_table(results), '']
    if any(name in suite_report.TARGETS for name in results):
        head += ['## The fleet profile against its targets', '',
                 suite_report.targets_table(results), '']
    suite_report.write_json(results, os.path.join(args.out, 'summary.json'))
    out = '\n'.join(head + text) + '\n'
    with open(os.path.join(args.out, 'report.md'), 'w') as stream:
        stream.write(out)
    return out


def main(argv=None):
    args = parse(sys.argv[1:] if argv is None else argv)
    options = default_options()
    status = guarded('evaluate --suite', lambda: None if args.analyze_only else [
        run_scenario(name, args.out, repeat, args.variants, options)
        for repeat in range(1, args.repeats + 1) for name in args.scenarios])
    if status:
        return status
    try:
        print(report(args))
    except (OSError, ValueError) as error:      # no bags, or a run with no task reported
        print('evaluate --suite: %s' % error, file=sys.stderr)
        return 1
    return 0
