"""The simulated league's report (no rospy): tables of medians with 95 % intervals over
the seeds, the fleet's paired differences, ``league.json``, ``league.md``, ``league.png``.

Every cell is ``median [low-high]``: the median over the seeds and its distribution-free
95 % interval (:func:`~server_select.sim.stats.median_interval`). ``mean / oracle`` is per
seed, to the oracle's run of the same seed. The paired table gives, per other variant,
the fleet's mean and p99 minus that variant's, per seed and in per cent of the oracle's
mean of that seed: the mean over the seeds and its 95 % t-interval (an interval wholly
below 0: the fleet is better beyond the noise).
"""

import json
import os

from server_select.core.util.league_columns import CAPACITY, NETWORK, shown
from server_select.core.util.tables import markdown_table
from server_select.sim.stats import median_interval, paired

ORACLE, FLEET = 'oracle_fleet', 'fleet'


def cell(values, spec, scale=1.0):
    median, low, high = median_interval(values)
    if median is None:
        return '-'
    pattern = spec + ' [' + spec + '-' + spec + ']'
    return pattern % (scale * median, scale * low, scale * high)


def _series(runs, seeds, key):
    return [runs[s].get(key) if s in runs else None for s in seeds]


def with_ratios(variants, seeds):
    """Each run's ``ratio``: its mean over the oracle's of the same seed (None: no oracle)."""
    oracle = variants.get(ORACLE, {})
    for runs in variants.values():
        for seed, row in runs.items():
            base = oracle.get(seed, {}).get('mean')
            row['ratio'] = row['mean'] / base if base and row.get('mean') else None
    return variants


def network_tables(name, variants, seeds):
    with_ratios(variants, seeds)
    columns = shown(NETWORK, [r for runs in variants.values() for r in runs.values()])
    rows = [[v] + [cell(_series(runs, seeds, key), spec, scale)
                   for key, _, spec, scale in columns]
            for v, runs in variants.items()]
    text = '### %s\n\n%s\n' % (name, markdown_table(
        ['variant'] + [title for _, title, _, _ in columns], rows))
    if FLEET in variants and ORACLE in variants:
        text += '\n' + paired_table(variants, seeds) + '\n'
    return text + '\n' + pick(variants, seeds) + '\n'


def pick(variants, seeds):
    """Which variant to pick on this scenario: the one of the least median mean round
    trip (failed tasks at the timeout), if the paired difference to the next best is below
    0 beyond the noise; else that there is no difference beyond the noise."""
    means = dict((v, median_interval(relative(variants, seeds, v, 'mean'))[0])
                 for v in variants if v != ORACLE and ORACLE in variants)
    ranked = sorted((m, v) for v, m in means.items() if m is not None)
    if len(ranked) < 2:
        return 'Pick: - (fewer than two variants with a mean to compare)'
    (_, best), (_, second) = ranked[:2]
    mean, low, high = paired_difference(variants, seeds, best, second, 'mean')
    if high < 0:
        return ('Pick: %s, its mean %.2f %% [%.2f, %.2f] of the oracle\'s below %s\'s '
                '(the next best; paired over %d seeds)'
                % (best, -mean, -high, -low, second, len(seeds)))
    return ('Pick: no difference beyond the noise between %s and %s (%+.2f %% [%+.2f, '
            '%+.2f] of the oracle\'s mean)' % (best, second, mean, low, high))


def relative(variants, seeds, variant, key):
    """``variant``'s ``key`` over the oracle's mean, per seed (None: not known)."""
    oracle, runs = variants[ORACLE], variants[variant]
    return [runs[s][key] / oracle[s]['mean'] if s in runs and s in oracle and
            oracle[s]['mean'] and runs[s].get(key) is not None else None for s in seeds]


def paired_difference(variants, seeds, name, base, key):
    """``(mean, low, high)`` of ``name``'s ``key`` minus ``base``'s, in per cent of the
    oracle's mean, per seed (None: no seed has both)."""
    mean, low, high = paired(relative(variants, seeds, name, key),
                             relative(variants, seeds, base, key))
    return None if mean is None else (100 * mean, 100 * low, 100 * high)


def differences(variants, seeds, other, key):
    """:func:`paired_difference` of the fleet minus ``other``."""
    return paired_difference(variants, seeds, FLEET, other, key)


def paired_table(variants, seeds):
    rows = []
    for other in [v for v in variants if v != FLEET]:
        cells = []
        for key in ('mean', 'p99'):
            d = differences(variants, seeds, other, key)
            cells.append('-' if d is None else '%+.2f [%+.2f, %+.2f]' % d)
        rows.append(['fleet - %s' % other] + cells)
    return markdown_table(["paired, % of the oracle's mean", 'mean', 'p99'], rows)


def capacity_tables(name, variants, seeds):
    static = variants.get('static', {})
    for runs in variants.values():
        for seed, row in runs.items():
            row['share'] = row['goodput'] / row['capacity']
            base = static.get(seed, {}).get('work')
            row['of_static'] = row['goodput'] / base if base else None
    columns = shown(CAPACITY, [r for runs in variants.values() for r in runs.values()])
    rows = [[v] + [cell(_series(runs, seeds, key), spec, scale)
                   for key, _, spec, scale in columns]
            for v, runs in variants.items()]
    return '### %s (capacity)\n\n%s\n' % (name, markdown_table(
        ['variant'] + [title for _, title, _, _ in columns], rows))


def plot(results, seeds, path):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    scenarios = list(results['network'])      # (in the order text() gave them)
    if not scenarios:
        return
    variants = [v for v in results['network'][scenarios[0]] if v != ORACLE]
    fig, ax = plt.subplots(figsize=(10, 4.5))
    width = 0.8 / max(1, len(variants))
    for index, variant in enumerate(variants):
        meds, errors = [], [[], []]
        for name in scenarios:
            median, low, high = median_interval(_series(
                results['network'][name].get(variant, {}), seeds, 'ratio'))
            meds.append(median or 0.0)
            errors[0].append((median - low) if median else 0.0)
            errors[1].append((high - median) if median else 0.0)
        ax.bar([i + index * width for i in range(len(scenarios))], meds, width,
               yerr=errors, capsize=2, label=variant)
    ax.axhline(1.0, color='black', linewidth=0.8)
    ax.set_xticks([i + 0.4 - width / 2 for i in range(len(scenarios))])
    ax.set_xticklabels(scenarios)
    ax.set_ylabel("mean round trip / the oracle's (median, 95 % interval)")
    ax.set_ylim(0.8, None)
    ax.legend(ncol=4, fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _ordered(variants, order):
    return dict((v, variants[v]) for v in sorted(
        variants, key=lambda v: order.index(v) if v in order else len(order)))


def text(results):
    seeds, order = results['seeds'], results.get('variants', {})
    for part in ('network', 'capacity'):
        results[part] = _ordered(results[part], results.get('scenarios', {}).get(part, []))
        for name in results[part]:
            results[part][name] = _ordered(results[part][name], order.get(part, []))
    parts = ['## The simulated league: %d seeds a cell (median [95 %% interval])\n'
             % len(seeds)]
    for name, variants in results['network'].items():
        parts.append(network_tables(name, variants, seeds))
    for name, variants in results['capacity'].items():
        parts.append(capacity_tables(name, variants, seeds))
    return '\n'.join(parts)


def load(path):
    """The results a ``league.json`` holds (its seeds as numbers again)."""
    with open(path) as stream:
        results = json.load(stream)
    for part in ('network', 'capacity'):
        for variants in results.get(part, {}).values():
            for variant, runs in list(variants.items()):
                variants[variant] = dict((int(seed), row) for seed, row in runs.items())
    return results


def write(results, out):
    """Write league.json, league.md and league.png into ``out``; returns the Markdown."""
    os.makedirs(out, exist_ok=True)
    body = text(results)        # (orders the results as asked: the plot follows it)
    with open(os.path.join(out, 'league.json'), 'w') as stream:
        json.dump(results, stream, indent=1, sort_keys=True)
    with open(os.path.join(out, 'league.md'), 'w') as stream:
        stream.write(body)
    plot(results, results['seeds'], os.path.join(out, 'league.png'))
    return body
