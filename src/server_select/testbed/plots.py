"""Plots of evaluation runs (matplotlib, imported only here)."""

import math
import warnings

from server_select.core.util.stats import percentile


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


def time_label(run):
    """What a run's times count from: a testbed scenario's start, or the bag's."""
    return 'scenario time (s)' if run.meta.get('scenario') else 'time since the bag started (s)'


def _labels(axes):
    """What each panel says (its title, axis labels and legend entries), for tests."""
    return [{'title': ax.get_title(), 'xlabel': ax.get_xlabel(), 'ylabel': ax.get_ylabel(),
             'legend': [t.get_text() for t in ax.get_legend().get_texts()]
             if ax.get_legend() else []} for ax in axes]


def legend_beside(ax, handles=None, labels=None, **kwargs):
    """The panel's legend to the right of it, outside, where it hides no point (with
    ``fig.tight_layout()``, which makes room for it)."""
    args = (handles, labels) if handles is not None else ()
    kwargs.setdefault('fontsize', 'small')
    ax.legend(*args, loc='upper left', bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
              **kwargs)


def _changes(flags):
    """The flags (sorted by time) that select another server than the one before."""
    return [f for f, before in zip(flags[1:], flags) if f.server != before.server]


def plain_log_ticks(ax, minor=False):
    """Plain labels on a log y axis (1, 10, 100), on its minor ticks too when ``minor``
    (True: all of them, for an axis within about a decade; or the leading digits to label,
    e.g. ``(2, 5)``)."""
    from matplotlib.ticker import FuncFormatter

    def label(v, _):
        digit = round(v / 10 ** math.floor(math.log10(v))) if v > 0 else 0
        return '%g' % v if minor is True or (minor and digit in minor) else ''
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: '%g' % v))
    ax.yaxis.set_minor_formatter(FuncFormatter(label))


def plot_task_rtt(runs, path):
    """Task round trip over time, one panel per robot, one line per mode (Fig. 8); failed
    tasks marked at the top; with one run, the flag changes as vertical lines. Returns what
    each panel says (:func:`_labels`)."""
    plt = pyplot()
    robots = sorted(set(r.robot for run in runs.values() for r in run.reports))
    fig, axes = plt.subplots(len(robots), 1, figsize=(12, 3.2 * len(robots)), squeeze=False)
    for ax, robot in zip(axes[:, 0], robots):
        for mode, run in runs.items():
            reports = sorted((r for r in run.reports if r.robot == robot), key=lambda r: r.t)
            line, = ax.plot([r.t for r in reports],
                            [r.rtt * 1e3 if r.ok else float('nan') for r in reports],
                            label=mode if len(runs) > 1 else 'answered task', linewidth=1)
            failed = [r.t for r in reports if not r.ok]
            if failed:
                ax.plot(failed, [1.0] * len(failed), 'x', color=line.get_color(),
                        transform=ax.get_xaxis_transform(), clip_on=False,
                        label='failed task (%s)' % mode if len(runs) > 1 else 'failed task')
        if len(runs) == 1:
            run = next(iter(runs.values()))
            flags = sorted((f for f in run.flags if f.robot == robot), key=lambda f: f.t)
            for i, f in enumerate(_changes(flags)):
                ax.axvline(f.t, color='grey', linestyle=':', linewidth=1,
                           label='flag selects another server' if i == 0 else None)
        ax.set_title('robot %d' % robot)
        ax.set_xlabel(time_label(next(iter(runs.values()))))
        ax.set_ylabel('task round trip (ms, log)')
        ax.set_yscale('log')
        low, high = ax.get_ylim()       # within a decade: 2, 3, 4, ... too; else 2 and 5
        plain_log_ticks(ax, minor=True if high < 20 * low else (2, 5))
        ax.grid(True, alpha=0.3)
        legend_beside(ax)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return _labels(axes[:, 0])


def _cut(ax, probes, ranked):
    """The round trip axis up to 1.5 x the larger of the ``probes``' 99th and the
    ``ranked`` statistics' 90th percentile (ms): a start-up spike would flatten the
    milliseconds that decide; the label says where it was cut."""
    tops = [percentile(sorted(values), q) for values, q in ((probes, 99), (ranked, 90))
            if values]
    top = 1.5 * max(tops) if tops and max(tops) > 0 else None
    clipped = top is not None and top < ax.get_ylim()[1]
    if clipped:
        ax.set_ylim(0, top)
    ax.set_ylabel('round trip (ms%s)' % ('; above %.3g cut' % top if clipped else ''))


def plot_latency(run, path, title):
    """Per robot: each server's probe round trips (dots), the statistic the manager ranked
    it by in each flag (dashed steps), the server each flag selects (shading, up to the
    next flag) and the moments the selection changed (vertical lines). Returns what each
    panel says (:func:`_labels`)."""
    plt = pyplot()
    from matplotlib.patches import Patch
    robots = sorted(set(s.robot for s in run.samples) | set(f.robot for f in run.flags))
    servers = sorted(set(s.server for s in run.samples) |
                     set(s for f in run.flags for s in f.ranking))
    colors = dict((s, 'C%d' % i) for i, s in enumerate(servers))
    fig, axes = plt.subplots(len(robots), 1, figsize=(12, 3.2 * len(robots)), squeeze=False)
    for ax, robot in zip(axes[:, 0], robots):
        samples = [s for s in run.samples if s.robot == robot]
        flags = sorted((f for f in run.flags if f.robot == robot), key=lambda f: f.t)
        end = max([s.t for s in samples] + [f.t for f in flags] or [0.0])
        for server in servers:
            # a failed probe breaks the line: no round trip is drawn across an outage
            pts = [(s.t, s.rtt * 1e3 if s.ok else float('nan')) for s in samples
                   if s.server == server]
            if any(s.ok for s in samples if s.server == server):
                ax.plot(*zip(*pts), '.', color=colors[server], markersize=3,
                        label='probes S%d' % server)
            ranked = [(f.t, m * 1e3) for f in flags for s, m in zip(f.ranking, f.means)
                      if s == server]
            if ranked:
                ax.step(*zip(*ranked), where='post', color=colors[server], linestyle='--',
                        linewidth=1.2, label='ranked by (flags) S%d' % server)
        for f, g in zip(flags, flags[1:] + [None]):
            if f.server in colors:
                ax.axvspan(f.t, g.t if g else end, color=colors[f.server], alpha=0.12,
                           linewidth=0)
        for i, f in enumerate(_changes(flags)):
            ax.axvline(f.t, color='grey', linestyle=':', linewidth=1,
                       label='selection changed' if i == 0 else None)
        handles, labels = ax.get_legend_handles_labels()
        if flags:
            handles.append(Patch(color='grey', alpha=0.25, linewidth=0))
            labels.append('shaded: the server the flag selects (its colour)')
        ax.set_title('%s: robot %d' % (title, robot))
        ax.set_xlabel(time_label(run))
        _cut(ax, [s.rtt * 1e3 for s in samples if s.ok],
             [m * 1e3 for f in flags for m in f.means])
        ax.grid(True, alpha=0.3)
        legend_beside(ax, handles, labels)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return _labels(axes[:, 0])
