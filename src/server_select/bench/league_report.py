"""The league's report (``make league``; :mod:`server_select.bench.league` runs it): what it
runs, the tables (median (min-max) of the runs per variant) and the plot."""

import collections
import os

from server_select.core.peers.balancers import PEERS
from server_select.core.util import league_columns
from server_select.core.util.tables import markdown_table, median_range

NETWORK_VARIANTS = ('oracle_fleet', 'fleet', 'fleet_hysteresis') + PEERS
# capacity cases: the capacity benchmark's scenario and what the league changes in it
CAPACITY = collections.OrderedDict([
    ('crowd', ['--scenario', 'crowd']),
    # the case: 6 robots, servers of 10, 15 and 20 % of a core, half to twice that
    ('overload_unequal', ['--scenario', 'overload', '--shares', '0.10,0.15,0.20']),
    ('herd', ['--scenario', 'herd']),
])
CAPACITY_VARIANTS = ('static', 'fleet', 'fleet_hysteresis') + PEERS


def _cell(values, spec, scale=1.0):
    known = [scale * v for v in values if v is not None]
    return median_range(known, spec) if known else '-'


def network_table(per_run):
    """One row per variant (the league's columns); ``ratio``: its mean over the oracle's of
    the same run."""
    for run in per_run:
        oracle = run.get('oracle_fleet') or {}
        for figures in run.values():
            figures['ratio'] = figures['mean'] / oracle['mean'] \
                if oracle.get('mean') and figures.get('mean') else None
    columns = league_columns.shown(league_columns.NETWORK,
                                   [f for run in per_run for f in run.values()])
    rows = [[v, len(runs)] + [_cell([f.get(k) for f in runs], spec, scale)
                              for k, _, spec, scale in columns]
            for v, runs in ((v, [r[v] for r in per_run if v in r]) for v in per_run[0])]
    return markdown_table(['variant', 'runs'] + [t for _, t, _, _ in columns], rows)


def capacity_table(rows):
    """One row per load and variant; goodput as a share of the servers' capacity (by CPU)
    and of what they finished under the static assignment in the same repeat."""
    groups = collections.OrderedDict()
    # what the servers finished under the best static assignment, same load and repeat
    # (servers kept busy: the capacity they really have, with every cost of a task)
    static = dict(((r['load'], r['repeat']), r.get('work')) for r in rows
                  if r['variant'] == 'static')
    for row in sorted(rows, key=lambda r: (r['load'], CAPACITY_VARIANTS.index(r['variant'])
                                           if r['variant'] in CAPACITY_VARIANTS else 99)):
        done = static.get((row['load'], row['repeat']))
        row = dict(row, share=row['goodput'] / row['capacity'],
                   of_static=row['goodput'] / done if done else None)
        groups.setdefault((row['load'], row['variant']), []).append(row)
    columns = league_columns.shown(league_columns.CAPACITY, [r for g in groups.values() for r in g])
    rows = [['%gx' % load, variant, len(group)] +
            [_cell([r.get(k) for r in group], spec, scale) for k, _, spec, scale in columns]
            for (load, variant), group in groups.items()]
    return markdown_table(['load', 'variant', 'runs'] + [t for _, t, _, _ in columns], rows)


def report(results, plot_path=None):
    text = ['# League', '', 'Each cell: median (min-max) over the runs. Failed tasks count '
            'at the task timeout in every mean and p99; switches and reactions from where '
            'tasks went. Reaction: from a change of the truly nearest server to the first '
            'task sent to it; reaction felt: from when the previous nearest server is 1 ms '
            'of round trip slower than the new one, or down (two ramps are equal where they '
            'cross).', '']
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
    import statistics
    from server_select.testbed.plots import pyplot
    plt = pyplot()
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
    # one colour per variant in both panels (the legend is shared)
    colors = dict((v, 'C%d' % i) for i, v in enumerate(collections.OrderedDict.fromkeys(
        CAPACITY_VARIANTS + NETWORK_VARIANTS)))
    for ax, title, bars in panels:
        cases = list(collections.OrderedDict.fromkeys(b[0] for b in bars))
        variants = list(collections.OrderedDict.fromkeys(b[1] for b in bars))
        width = 0.8 / max(1, len(variants))
        for i, variant in enumerate(variants):
            values = [next((statistics.median(b[2]) for b in bars if b[0] == c and
                            b[1] == variant and b[2]), 0.0) for c in cases]
            ax.bar([x + i * width for x in range(len(cases))], values, width, label=variant,
                   color=colors[variant])
        ax.set_xticks([x + 0.4 - width / 2 for x in range(len(cases))])
        ax.set_xticklabels(cases, rotation=20, fontsize=8)
        ax.set_title(title, fontsize=10)
    axes[0].axhline(1.0, color='k', lw=0.5)
    shown = collections.OrderedDict()        # every variant of either panel, once
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            shown.setdefault(label, handle)
    handles, labels = list(shown.values()), list(shown)
    if labels:
        fig.legend(handles, labels, loc='lower center', ncol=len(labels), fontsize=8,
                   frameon=False)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(path, dpi=90)
    plt.close(fig)
