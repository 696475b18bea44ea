"""``rosrun server_select analyze BAG [BAG ...]``: the report tables of any recorded run.

Any bag holding the package's topics will do (``rosbag record -a`` during ``demo.launch``,
the evaluation's bags, a namespaced fleet): one row per bag, named by the evaluation's
metadata beside it or by the bag's file name. With ``--scenario`` (or the evaluation's
metadata) the reaction to each change of the truly nearest server is computed too;
without it there are no oracle columns. ``--out DIR`` also writes report.md, summary.json
and the plots there. A bag with none of the topics is refused with one line (exit 2).
"""

import argparse
import collections
import os
import sys

from rosbag import ROSBagException

from server_select.testbed import bag_analysis, bag_tables, switch_table
from server_select.testbed.scenario import Scenario, ScenarioError


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog='analyze', description='The report table of any recorded run of server_select.',
        epilog='Without a scenario (--scenario, or an evaluation bag\'s metadata) the table '
        'has no reaction columns: they need the truly nearest server over time.')
    parser.add_argument('bags', nargs='+', metavar='BAG')
    parser.add_argument('--scenario', help='scenario YAML the run followed (optional)')
    parser.add_argument('--out', help='also write report.md, summary.json and plots here')
    args = parser.parse_args(argv)
    runs = collections.OrderedDict()
    try:
        for path in args.bags:
            run = bag_analysis.load(path)
            if not (run.reports or run.flags or run.samples):
                raise ValueError('%s has none of the topics %s' % (
                    path, ', '.join(bag_analysis.TOPICS)))
            name = run.meta.get('mode') or os.path.splitext(os.path.basename(path))[0]
            runs[name if name not in runs else path] = run
        source = args.scenario or next(iter(runs.values())).meta.get('scenario')
        scenario = Scenario.load(source) if source else None
    except (OSError, ValueError, ScenarioError, ROSBagException) as error:
        print('analyze: %s' % error, file=sys.stderr)
        return 2
    duration = next(iter(runs.values())).meta.get('duration')
    summaries = bag_analysis.summarize_runs(runs, scenario, duration)
    if args.out:
        bag_analysis.write_report(runs, summaries, args.out, 'Analysis of %d bag(s)' % len(runs),
                                  'Bags: %s.' % ', '.join('`%s`' % b for b in args.bags))
    first = 'mode' if all(run.meta.get('mode') for run in runs.values()) else 'run'
    print('%s\n\n%s' % (bag_tables.table(summaries, first), bag_tables.legend(summaries)))
    for name, run in runs.items():
        found = switch_table.switches(run.reports, run.flags)
        shown = switch_table.table(found, 20 if args.out else None) if found else ''
        print('\nswitches of %s: %d%s' % (name, len(found), '\n\n' + shown if shown else ''))
    if args.out:
        print('report: %s (plots beside it)' % os.path.join(args.out, 'report.md'))
    return 0


if __name__ == '__main__':
    sys.exit(main())
