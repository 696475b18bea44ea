"""Plots of one suite run: round trips on the scenario's time axis and their CDF."""

import collections

from server_select.testbed.plots import legend_beside, pyplot

SHOWN = ('fixed', 'oracle', 'paper', 'fleet')     # drawn bold; the other variants thin


def _by_robot(run, owners):
    """``{scenario robot: {variant: [reports]}}``."""
    out = collections.defaultdict(lambda: collections.defaultdict(list))
    for report in run.reports:
        if report.robot in owners:
            variant, robot = owners[report.robot]
            out[robot][variant].append(report)
    return out


def plot_time(run, owners, changes, timeout, path, title):
    """Round trip of every task against scenario time, one panel per scenario robot, one
    colour per variant; failed tasks as crosses at the timeout; dashed lines where the
    truly nearest server changes; log latency axis."""
    plt = pyplot()
    per_robot = _by_robot(run, owners)
    robots = sorted(per_robot)
    if not robots:
        raise ValueError('%s: no robot reported a task (see the run folder\'s robot logs)'
                         % title)
    fig, axes = plt.subplots(len(robots), 1, figsize=(14, 3.4 * len(robots)), squeeze=False)
    for ax, robot in zip(axes[:, 0], robots):
        for index, (variant, reports) in enumerate(sorted(per_robot[robot].items())):
            color = 'C%d' % index
            ok = sorted((r.t, r.rtt * 1e3) for r in reports if r.ok)
            bold = variant in SHOWN
            if ok:
                ax.plot(*zip(*ok), '-', color=color, linewidth=1.1 if bold else 0.5,
                        alpha=1.0 if bold else 0.6, label=variant)
            failed = [r.t for r in reports if not r.ok]
            if failed:
                ax.plot(failed, [timeout * 1e3] * len(failed), 'x', color=color,
                        markersize=6, label='%s failed (%d)' % (variant, len(failed)))
        for t, _robot, server in (c for c in changes if c[1] == robot):
            ax.axvline(t, color='k', linestyle='--', linewidth=0.8)
            ax.annotate('S%d' % server, (t, 1.0), xycoords=('data', 'axes fraction'),
                        fontsize='small', va='top')
        ax.set_yscale('log')
        ax.set_title('%s: robot %d (dashed: the truly nearest server changes)' % (title, robot))
        ax.set_xlabel('scenario time (s)')
        ax.set_ylabel('task round trip (ms, log)')
        ax.grid(True, alpha=0.3)
        legend_beside(ax, fontsize='x-small')
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def plot_cdf(run, owners, timeout, start, path, title):
    """CDF of the task round trips of each variant (failed tasks at the timeout)."""
    plt = pyplot()
    values = collections.defaultdict(list)
    for report in run.reports:
        if report.robot in owners and report.t >= start:
            values[owners[report.robot][0]].append(report.rtt if report.ok else timeout)
    fig, ax = plt.subplots(figsize=(10, 5))
    for variant, rtts in sorted(values.items()):
        rtts = sorted(v * 1e3 for v in rtts)
        ax.step(rtts, [(i + 1) / float(len(rtts)) for i in range(len(rtts))], where='post',
                linewidth=1.4 if variant in SHOWN else 0.7, label=variant)
    ax.set_xscale('log')
    ax.set_xlabel('task round trip (ms, log; failed at the %g s timeout)' % timeout)
    ax.set_ylabel('fraction of tasks')
    ax.set_title('%s: round trips of all robots' % title)
    ax.grid(True, alpha=0.3)
    legend_beside(ax)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
