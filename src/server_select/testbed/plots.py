"""Plots of evaluation runs (matplotlib, imported only here)."""

import warnings


def pyplot():
    """matplotlib's pyplot, drawing to files. Where Debian's python3-matplotlib is installed
    beside the venv's, its mpl_toolkits makes matplotlib warn that 3-D plots are unavailable:
    none is drawn here, so that warning is not shown."""
    with warnings.catch_warnings():
        warnings.filterwarnings('ignore', message='Unable to import Axes3D')
        import matplotlib
        matplotlib.use('Agg')
        import matplotlib.pyplot as plt
    return plt


def plot_task_rtt(runs, path):
    """Task round trip vs task index, one panel per robot, one line per mode (Fig. 8)."""
    plt = pyplot()
    robots = sorted(set(r.robot for run in runs.values() for r in run.reports))
    fig, axes = plt.subplots(len(robots), 1, figsize=(9, 3.2 * len(robots)), squeeze=False)
    for ax, robot in zip(axes[:, 0], robots):
        for mode, run in runs.items():
            reports = sorted((r for r in run.reports if r.robot == robot), key=lambda r: r.task)
            ax.plot([r.task for r in reports],
                    [r.rtt * 1e3 if r.ok else float('nan') for r in reports],
                    label=mode, linewidth=1)
        ax.set_title('robot %d' % robot)
        ax.set_xlabel('task index')
        ax.set_ylabel('round trip (ms, log)')
        ax.set_yscale('log')
        ax.grid(True, alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_latency(run, path, title):
    """Probe round trip per pair over time, the selected server overlaid, per robot."""
    plt = pyplot()
    robots = sorted(set(s.robot for s in run.samples) | set(f.robot for f in run.flags))
    servers = sorted(set(s.server for s in run.samples))
    colors = dict((s, 'C%d' % i) for i, s in enumerate(servers))
    fig, axes = plt.subplots(len(robots), 1, figsize=(9, 3.2 * len(robots)), squeeze=False)
    for ax, robot in zip(axes[:, 0], robots):
        for server in servers:
            # a failed probe breaks the line: no round trip is drawn across an outage
            pts = [(s.t, s.rtt * 1e3 if s.ok else float('nan')) for s in run.samples
                   if s.robot == robot and s.server == server]
            if any(s.ok for s in run.samples if s.robot == robot and s.server == server):
                ax.plot(*zip(*pts), '.-', color=colors[server], markersize=3, linewidth=0.8,
                        label='probe S%d' % server)
        flags = sorted((f for f in run.flags if f.robot == robot), key=lambda f: f.t)
        for f, g in zip(flags, flags[1:] + [None]):
            if f.server in colors:
                ax.axvspan(f.t, g.t if g else f.t + 1.0, color=colors[f.server], alpha=0.12,
                           linewidth=0)
        ax.set_title('%s: robot %d (shading: selected server)' % (title, robot))
        ax.set_xlabel('scenario time (s)')
        ax.set_ylabel('probe round trip (ms)')
        ax.grid(True, alpha=0.3)
        ax.legend(loc='upper left', fontsize='small')
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
