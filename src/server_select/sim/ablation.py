"""The ablation table of a simulated league (no rospy): each variant against a base, per
seed, in every scenario (``python3 -m server_select.sim.ablation league.json``).

A network cell is the paired difference of the mean in per cent of the oracle's mean,
with its 95 % interval; a capacity cell the paired difference of goodput (per cent of
capacity) and of failed tasks. ``variant - base``: a mechanism switched off
(``fleet~keep``) that makes the mean higher is one that pays. ``--add NAME=FILE:VARIANT``
brings a variant of another league's results (same seeds: e.g. the rule before a change).
``--fields`` sums up many network scenarios (``gen:1-200``) in one row per variant.
"""

import argparse
import sys

from server_select.sim import report
from server_select.sim.stats import paired
from server_select.core.util.tables import markdown_table

CAPACITY_KEYS = (('share', 'goodput %', 100.0), ('failed', 'failed', 1.0))


def _cell(difference):
    if difference is None or difference[0] is None:
        return '-'
    mean, low, high = difference
    mark = '**' if low > 0 or high < 0 else ''      # beyond its interval
    return '%s%+.2f [%+.2f, %+.2f]%s' % (mark, mean, low, high, mark)


def capacity_cell(variants, seeds, name, base, key, scale):
    def series(variant):
        return [variants[variant][s][key] * scale if s in variants[variant] else None
                for s in seeds]
    return paired(series(name), series(base))


def table(results, base='fleet'):
    """The Markdown ablation table of ``results`` (a league's, :func:`report.load`)."""
    seeds = results['seeds']
    network = [(n, v) for n, v in results['network'].items() if base in v]
    capacity = [(n, v) for n, v in results['capacity'].items() if base in v]
    for name, variants in capacity:
        report.capacity_tables(name, variants, seeds)          # (adds each run's share)
    names = []
    for _, variants in network + capacity:
        names += [v for v in variants if v not in names and v not in
                  (base, report.ORACLE, 'static')]
    rows = []
    for scenario, variants in network:
        rows.append(['%s mean' % scenario] + [
            _cell(report.paired_difference(variants, seeds, name, base, 'mean'))
            if name in variants and report.ORACLE in variants else '-' for name in names])
    for scenario, variants in capacity:
        rows += [['%s %s' % (scenario, title)] + [
            _cell(capacity_cell(variants, seeds, name, base, key, scale))
            if name in variants else '-' for name in names]
            for key, title, scale in CAPACITY_KEYS]
    header = ['%s minus %s (95 %% interval)' % ('variant', base)] + names
    return markdown_table(header, rows)


def fields_table(results, base='fleet', margin=1.0):
    """Over many network scenarios (generated fields): each variant against ``base``, the
    paired difference of the mean over every (scenario, seed) in per cent of the oracle's
    mean, and the share of scenarios where ``base``'s mean is no worse than the
    variant's + ``margin`` per cent of the oracle's."""
    seeds, rows = results['seeds'], []
    network = [v for v in results['network'].values() if base in v and report.ORACLE in v]
    names = sorted(set(n for v in network for n in v) - {base, report.ORACLE})
    for name in names:
        pairs = [100 * (x - y) for v in network if name in v
                 for x, y in zip(report.relative(v, seeds, name, 'mean'),
                                 report.relative(v, seeds, base, 'mean'))
                 if x is not None and y is not None]
        per_field = [d[0] for d in (report.paired_difference(v, seeds, name, base, 'mean')
                                    for v in network if name in v) if d is not None]
        mean, low, high = paired(pairs, [0.0] * len(pairs))
        rows.append([name, str(len(per_field)), _cell((mean, low, high)),
                     '%.0f %%' % (100.0 * sum(d >= -margin for d in per_field) /
                                  max(1, len(per_field)))])
    return markdown_table(['variant', 'fields', 'variant minus %s, %% of the oracle (95 %% '
                           'interval)' % base, '%s no worse (within %g %%)' % (base, margin)],
                          rows)


def add(results, spec):
    """Bring ``NAME=FILE:VARIANT`` into ``results`` as variant NAME."""
    name, _, source = spec.partition('=')
    path, _, which = source.rpartition(':')
    other = report.load(path)
    for part in ('network', 'capacity'):
        for scenario, variants in other.get(part, {}).items():
            if which in variants and scenario in results[part]:
                results[part][scenario][name] = variants[which]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('results', help="a league's league.json")
    parser.add_argument('--base', default='fleet')
    parser.add_argument('--add', action='append', default=[], metavar='NAME=FILE:VARIANT')
    parser.add_argument('--fields', action='store_true', help='one summary over all '
                        'network scenarios (generated fields) instead of a row each')
    args = parser.parse_args(argv)
    results = report.load(args.results)
    for spec in args.add:
        add(results, spec)
    print(fields_table(results, args.base) if args.fields else table(results, args.base))
    return 0


if __name__ == '__main__':
    sys.exit(main())
