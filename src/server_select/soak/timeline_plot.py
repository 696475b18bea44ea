"""The soak's timeline (matplotlib, imported only here): faults shaded, each robot's round
trips (median per bin of its answered tasks), failed tasks per bin, and RSS per node."""

import collections

from server_select.core.util.stats import percentile
from server_select.soak.plan import ROBOTS
from server_select.testbed.plots import legend_beside, pyplot

BIN = 5.0       # s


def _binned(points, t0):
    bins = collections.defaultdict(list)
    for t, value in points:
        bins[int((t - t0) // BIN)].append(value)
    return sorted((b * BIN + BIN / 2, values) for b, values in bins.items())


def draw(path, rows, hist, samples, t0):
    plt = pyplot()
    fig, (rtt, failed, rss) = plt.subplots(3, 1, figsize=(12, 9), sharex=True)
    for ax in (rtt, failed, rss):
        for row in rows:
            ax.axvspan(row['at'], row['at'] + max(row['lasted'], 0.5), color='tab:red',
                       alpha=0.15, lw=0)
    for robot in ROBOTS:
        mine = [(r.t, r.rtt * 1e3) for r in hist.reports if r.robot == robot and r.ok
                and r.kind == 'sort']
        series = [(t, percentile(v, 50)) for t, v in _binned(mine, t0)]
        if series:
            rtt.plot(*zip(*series), lw=0.8, label='robot %d' % robot)
    rtt.set_yscale('log')
    rtt.set_ylabel('sort task round trip,\nmedian per %g s (ms)' % BIN)
    rtt.set_title('Soak: faults shaded (kind above), tasks and memory')
    for row in rows:
        rtt.annotate(row['kind'].replace('_', ' '), (row['at'], 1.0), xycoords=(
            'data', 'axes fraction'), rotation=90, fontsize=6, va='top')
    legend_beside(rtt)
    fails = _binned([(r.t, 1) for r in hist.reports if not r.ok], t0)
    if fails:
        failed.bar([t for t, _ in fails], [len(v) for _, v in fails], width=BIN,
                   color='tab:red')
    failed.set_ylabel('failed tasks per %g s' % BIN)
    rss.set_prop_cycle(color=plt.cm.tab20.colors)     # a colour for each node
    nodes = collections.defaultdict(list)
    for s in samples:
        nodes[s.node].append((s.t - t0, s.rss_mib))
    for node, points in sorted(nodes.items()):
        rss.plot(*zip(*points), lw=0.8, label=node)
    rss.set_ylabel('RSS (MiB)')
    rss.set_xlabel('soak time (s)')
    legend_beside(rss, ncol=1)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
