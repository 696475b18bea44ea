"""Analysis of evaluation bags: tables and plots recomputed from the bags alone.

``load`` reads one bag with the rosbag API (times relative to the scenario's t0 from the
``<bag>.json`` written beside it); the other functions are pure and unit-tested.
"""

import collections
import json
import math
import os

from server_select.testbed.scenario import Scenario
from server_select.core.stats import summarize
from server_select.core.tables import fmt, markdown_table

Flag = collections.namedtuple('Flag', 't robot server ranking means')
Report = collections.namedtuple('Report', 't robot task ok rtt server answered_by error')
Sample = collections.namedtuple('Sample', 't robot server ok rtt')
Run = collections.namedtuple('Run', 'meta flags reports samples')


def load(bag_path):
    """A :class:`Run` from a bag and its metadata (times: seconds since scenario t0)."""
    import rosbag  # only here: the pure functions below need no ROS
    with open(bag_path + '.json') as stream:
        meta = json.load(stream)
    t0 = meta['t0']
    flags, reports, samples = [], [], []
    with rosbag.Bag(bag_path) as bag:
        for topic, msg, stamp in bag.read_messages():
            t = stamp.to_sec() - t0
            name = topic.rsplit('/', 1)[-1]
            if name == 'server_select_flag':
                flags.append(Flag(t, msg.robot_id, msg.server_id, list(msg.ranking),
                                  list(msg.mean_latency)))
            elif name == 'task_report':
                reports.append(Report(t, msg.robot_id, msg.task_id, msg.ok, msg.rtt,
                                      msg.server_id, msg.answered_by, msg.error))
            elif name.startswith('latency_R'):
                samples.append(Sample(t, msg.robot_id, msg.server_id, msg.ok, msg.rtt))
    return Run(meta, flags, reports, samples)


def switches(reports):
    """Changes of the server a robot sent its tasks to (in task order), per robot.

    Counted from the robots' task reports, so that a fixed robot shows none whatever the
    manager publishes; tasks sent with no server selected do not count.
    """
    counts = collections.Counter()
    by_robot = collections.defaultdict(list)
    for r in reports:
        if r.server >= 0:
            by_robot[r.robot].append((r.task, r.server))
    for robot, tasks in by_robot.items():
        servers = [server for _, server in sorted(tasks)]
        counts[robot] = sum(1 for a, b in zip(servers, servers[1:]) if a != b)
    return counts


def oracle_changes(scenario, robots, start, end, step=0.05):
    """``[(t, robot, new_server)]``: when the truly nearest server of a robot changes."""
    changes = []
    for robot in robots:
        previous = scenario.nearest_server(robot, start)
        n = int(math.floor((end - start) / step))
        for i in range(1, n + 1):
            t = start + i * step
            nearest = scenario.nearest_server(robot, t)
            if nearest != previous:
                changes.append((t, robot, nearest))
                previous = nearest
    return sorted(changes)


def reaction_times(flags, changes):
    """For each oracle change, seconds until the flags select the new nearest server.

    Returns ``[(t_change, robot, new_server, reaction or None)]``; None means the flags did
    not reach the new server before the robot's next change (or the run's end).
    """
    by_robot = collections.defaultdict(list)
    for f in sorted(flags, key=lambda f: f.t):
        by_robot[f.robot].append(f)
    results = []
    for i, (t, robot, server) in enumerate(changes):
        following = [c[0] for c in changes[i + 1:] if c[1] == robot]
        limit = following[0] if following else float('inf')
        before = [f for f in by_robot[robot] if f.t < t]
        if before and before[-1].server == server:
            results.append((t, robot, server, 0.0))
            continue
        hit = next((f for f in by_robot[robot] if t <= f.t < limit and f.server == server),
                   None)
        results.append((t, robot, server, hit.t - t if hit else None))
    return results


def mode_summary(run_reports, flags, changes=None):
    """The figures of one mode: task counts, round-trip statistics, switches, reactions."""
    ok = [r.rtt for r in run_reports if r.ok]
    rtt = summarize(ok)
    summary = {
        'tasks': len(run_reports),
        'failed': sum(1 for r in run_reports if not r.ok),
        'rtt_ms': dict((k, v * 1e3) for k, v in rtt.items() if k != 'n'),
        'switches': sum(switches(run_reports).values()),
    }
    if changes is not None:
        reactions = reaction_times(flags, changes)
        reached = [r[3] for r in reactions if r[3] is not None]
        summary['reactions'] = [{'t': r[0], 'robot': r[1], 'server': r[2], 'seconds': r[3]}
                                for r in reactions]
        summary['reaction_mean_s'] = sum(reached) / len(reached) if reached else None
        summary['reaction_max_s'] = max(reached) if reached else None
        summary['reaction_missed'] = len(reactions) - len(reached)
    return summary


def compare(summaries):
    """Add improvement vs ``fixed`` and gap to ``oracle`` (by mean round trip, %)."""
    def mean(mode):
        return summaries.get(mode, {}).get('rtt_ms', {}).get('mean')
    for mode, s in summaries.items():
        m = s.get('rtt_ms', {}).get('mean')
        s['vs_fixed_pct'] = (100.0 * (mean('fixed') - m) / mean('fixed')
                             if m is not None and mean('fixed') else None)
        s['gap_to_oracle_pct'] = (100.0 * (m - mean('oracle')) / mean('oracle')
                                  if m is not None and mean('oracle') else None)
    return summaries


def table(summaries):
    """Markdown table of :func:`mode_summary` results, one row per mode."""
    rows = []
    for mode, s in summaries.items():
        r = s['rtt_ms']
        reaction = '-'
        if s.get('reactions'):
            reaction = '%s / %s (%d)' % (fmt(s['reaction_mean_s']), fmt(s['reaction_max_s']),
                                         s['reaction_missed'])
        rows.append([mode, s['tasks'], s['failed']]
                    + [fmt(r.get(k)) for k in ('mean', 'median', 'p95', 'p99', 'max')]
                    + [fmt(s.get('vs_fixed_pct'), '%+.1f %%'),
                       fmt(s.get('gap_to_oracle_pct'), '%+.1f %%'), s['switches'], reaction])
    return markdown_table(
        ('mode', 'tasks', 'failed', 'mean ms', 'median ms', 'p95 ms', 'p99 ms', 'max ms',
         'vs fixed', 'gap to oracle', 'switches', 'reaction mean / max s (missed)'), rows)


def plot_task_rtt(runs, path):
    """Task round trip vs task index, one panel per robot, one line per mode (Fig. 8)."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
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
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    robots = sorted(set(s.robot for s in run.samples) | set(f.robot for f in run.flags))
    servers = sorted(set(s.server for s in run.samples))
    colors = dict((s, 'C%d' % i) for i, s in enumerate(servers))
    fig, axes = plt.subplots(len(robots), 1, figsize=(9, 3.2 * len(robots)), squeeze=False)
    for ax, robot in zip(axes[:, 0], robots):
        for server in servers:
            pts = [(s.t, s.rtt * 1e3) for s in run.samples
                   if s.robot == robot and s.server == server and s.ok]
            if pts:
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


def analyze(out_dir, modes):
    """Read ``<out_dir>/<mode>.bag`` for each mode; write report.md, summary.json, PNGs."""
    runs = collections.OrderedDict()
    for mode in modes:
        bag = os.path.join(out_dir, '%s.bag' % mode)
        if os.path.exists(bag):
            runs[mode] = load(bag)
    if not runs:
        raise FileNotFoundError('no bags of modes %s in %s' % (modes, out_dir))
    meta = next(iter(runs.values())).meta
    scenario = Scenario.load(meta['scenario'])
    robots = [h.id for h in scenario.of_role('robot')]
    changes = oracle_changes(scenario, robots, 0.0, meta['duration'])
    summaries = collections.OrderedDict(
        (mode, mode_summary(run.reports, run.flags, changes if mode != 'fixed' else None))
        for mode, run in runs.items())
    compare(summaries)
    with open(os.path.join(out_dir, 'summary.json'), 'w') as stream:
        json.dump(summaries, stream, indent=1)
    plot_task_rtt(runs, os.path.join(out_dir, 'task_rtt.png'))
    for mode, run in runs.items():
        plot_latency(run, os.path.join(out_dir, 'latency_%s.png' % mode), mode)
    text = ['# Evaluation: %s' % scenario.name, '',
            'Scenario `%s`, %.0f s per mode; task round trip from the robots\' `task_report`; '
            'improvement and gap by mean round trip; reaction: from a change of the truly '
            'nearest server to the flag selecting it.'
            % (os.path.basename(meta['scenario']), meta['duration']), '',
            table(summaries), '',
            '![task round trip](task_rtt.png)', '']
    text += ['![latency %s](latency_%s.png)' % (m, m) for m in runs]
    report = '\n'.join(text) + '\n'
    with open(os.path.join(out_dir, 'report.md'), 'w') as stream:
        stream.write(report)
    return report
