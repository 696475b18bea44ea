"""The capacity benchmark's figures, table and plot, from its bags (see bench/capacity.py)."""

import collections
import glob
import os
import re
import statistics

import numpy as np

from server_select.core.util.tables import fmt, markdown_table, median_range

COLUMNS = (('offered', 'offered /s', '%.2f', 1.0), ('sent', 'sent /s', '%.2f', 1.0),
           ('goodput', 'goodput /s', '%.2f', 1.0),
           ('share', 'goodput / measured capacity %', '%.0f', 100.0),
           ('failed', 'failed', '%d', 1.0), ('mean', 'mean ms', '%.0f', 1e3),
           ('p50', 'p50 ms', '%.0f', 1e3), ('p99', 'p99 ms', '%.0f', 1e3),
           ('oldest', 'oldest answer ms', '%.0f', 1e3), ('extra', 'extra sends %', '%.1f', 100.0),
           ('work', 'server work /s', '%.2f', 1.0), ('wanted', 'work wanted %', '%.0f', 100.0),
           ('switches', 'switches /min /robot', '%.1f', 1.0),
           ('settled', 'settled switches /min /robot', '%.1f', 1.0),
           ('overloaded', 'longest overload s', '%.0f', 1.0),
           ('settled_overload', 'settled longest overload s', '%.0f', 1.0))


WORKED = re.compile(r'\[INFO\] \[([0-9.]+)\]: server ([0-9]+): .*?([0-9]+) tasks worked on')


def static_assignment(shares, robots):
    """``{robot: server}``: robots to servers in proportion to their shares (D'Hondt)."""
    count = collections.Counter()
    assigned = {}
    for robot in range(1, robots + 1):
        server = min(range(1, len(shares) + 1),
                     key=lambda s: ((count[s] + 1) / shares[s - 1], s))
        count[server] += 1
        assigned[robot] = server
    return assigned


def work_rate(run_dir, t0, start, end):
    """Tasks/s the servers worked on between scenario times ``start`` and ``end``, from
    the periodic summary lines in their logs (``run_dir/ros_home/<host>/log``); None when
    a server logged fewer than two lines in that time."""
    counts = collections.defaultdict(list)
    for path in glob.glob(os.path.join(run_dir, 'ros_home', '*', 'log', '*', '*-stdout.log')):
        with open(path, errors='replace') as stream:
            for match in WORKED.finditer(stream.read()):
                t = float(match.group(1)) - t0
                if start <= t <= end:
                    counts[int(match.group(2))].append((t, int(match.group(3))))
    rates = []
    for points in counts.values():
        points = sorted(set(points))
        if len(points) < 2:
            return None
        rates.append((points[-1][1] - points[0][1]) / (points[-1][0] - points[0][0]))
    return sum(rates) if rates else None


def detections(bag_path, t0):
    """``[(t, robot, task, server)]`` of the servers' ``detections`` (one per frame done)."""
    from server_select.ros import bags
    return [(t - t0, m.robot_id, m.task_id, m.server_id)
            for _, m, t, _ in bags.read(bag_path, {'detections'})]


def overloaded(reports, capacities, timeout, start, end, span=2.0, slack=1.25):
    """The longest time (s) that some server was sent more than ``slack`` x its capacity
    (``capacities[server]``, tasks/s), in sliding ``span`` s windows (a stretch counts from
    the first such window's start to the last one's end; a task is sent at its report's
    time less its round trip, or less the timeout when it failed)."""
    sent = collections.defaultdict(list)
    for r in reports:
        sent[r.server].append(r.t - (r.rtt if r.ok else timeout))
    longest = 0.0
    for server, capacity in capacities.items():
        times, run_start = np.sort(sent.get(server, [])), None
        for t in np.arange(start, end, 0.25):
            count = np.searchsorted(times, t + span) - np.searchsorted(times, t)
            if count > slack * capacity * span:
                run_start = t if run_start is None else run_start
                longest = max(longest, t + span - run_start)
            else:
                run_start = None
    return longest


def placed(run):
    """Scenario time of the last robot's first task report (robots placed by then)."""
    first = {}
    for r in run.reports:
        first[r.robot] = min(r.t, first.get(r.robot, r.t))
    return max(first.values()) if first else 0.0


def figures(run, done, offered, start, end, timeout, capacities=None, settled=None):
    """The figures of one run: ``run`` a bag_analysis Run, ``done`` its detections (None:
    not frames), ``offered`` tasks/s the robots were asked to send, ``capacities`` each
    server's tasks/s; from scenario time ``settled`` on (None: no such figure), the
    switches and the longest overload again: after a change the robots had to follow (a
    server came up)."""
    from server_select.testbed.bag_analysis import switches
    seconds = end - start
    reports = [r for r in run.reports if start <= r.t < end]
    rtts = np.array([r.rtt if r.ok else timeout for r in reports]) if reports \
        else np.array([timeout])
    ok = [r for r in reports if r.ok]
    attempts = [max(1, r.attempts) for r in reports]
    row = {'offered': offered, 'sent': len(reports) / seconds,
           'goodput': len(ok) / seconds, 'failed': len(reports) - len(ok),
           'tasks': len(reports), 'mean': float(rtts.mean()),
           'p50': float(np.percentile(rtts, 50)), 'p99': float(np.percentile(rtts, 99)),
           'oldest': max([r.rtt for r in ok] or [0.0]),
           'extra': (sum(attempts) - len(attempts)) / max(1, len(reports)),
           'switches': sum(switches(reports).values()) * 60.0 / seconds / max(
               1, len(set(r.robot for r in reports)))}
    if settled is not None:
        late = [r for r in reports if r.t >= settled]
        row['settled'] = sum(switches(late).values()) * 60.0 / max(1e-9, end - settled) / max(
            1, len(set(r.robot for r in late)))
    if capacities:
        row['overloaded'] = overloaded(reports, capacities, timeout, start, end)
        if settled is not None:
            row['settled_overload'] = overloaded(reports, capacities, timeout, settled, end)
    if done is not None:
        answered = set((r.robot, r.task, r.answered_by) for r in run.reports if r.ok)
        mine = [d for d in done if start <= d[0] < end]
        row['wanted'] = sum(1 for _, robot, task, server in mine
                            if (robot, task, server) in answered) / max(1, len(mine))
    return row


def line(row):
    """One run as a line of text (printed while the benchmark runs)."""
    return '%s x%g: ' % (row['variant'], row['load']) + ', '.join(
        '%s %s' % (title, fmt(None if row[key] is None else scale * row[key], spec))
        for key, title, spec, scale in COLUMNS if key in row)


def measured(runs):
    """The most work the servers were seen to do (tasks/s), over ``runs``: their capacity
    as measured (None: no run logged it)."""
    seen = [r['work'] for r in runs if r.get('work') is not None]
    return max(seen) if seen else None


def table(kind, runs, capacity):
    groups = collections.OrderedDict()
    capacity = measured(runs) or capacity
    for row in sorted(runs, key=lambda r: (r['load'], r['variant'])):
        row = dict(row, share=row['goodput'] / capacity)
        groups.setdefault((row['load'], row['variant']), []).append(row)
    keys = [c for c in COLUMNS if all(r.get(c[0]) is not None for g in groups.values()
                                      for r in g)]
    return markdown_table(
        ['load x capacity', 'variant'] + [title for _, title, _, _ in keys],
        [['%g' % load, variant] + [median_range([scale * r[key] for r in group], spec)
                                   for key, _, spec, scale in keys]
         for (load, variant), group in groups.items()])


def plot(results, path):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from server_select.testbed.plots import legend_beside, plain_log_ticks
    kinds = list(results['kinds'])
    fig, axes = plt.subplots(2, len(kinds), figsize=(8 * len(kinds), 7), squeeze=False)
    for column, kind in enumerate(kinds):
        info = results['kinds'][kind]
        by_variant = collections.defaultdict(lambda: collections.defaultdict(list))
        for row in info['runs']:
            by_variant[row['variant']][row['load']].append(row)
        for variant, loads in sorted(by_variant.items()):
            xs = sorted(loads)
            for axis, key, scale in ((axes[0][column], 'goodput', 1.0),
                                     (axes[1][column], 'mean', 1e3)):
                ys = [statistics.median(scale * r[key] for r in loads[x]) for x in xs]
                axis.plot([x * info['capacity'] for x in xs], ys, marker='o', label=variant)
        top, bottom = axes[0][column], axes[1][column]
        top.axhline(measured(info['runs']) or info['capacity'], color='grey', linestyle=':',
                    label='measured capacity')
        top.set_title('%s tasks: goodput (answered within %g s)' % (kind, results['timeout']))
        top.set_ylabel('answers wanted per s')
        bottom.set_title('%s tasks: mean round trip (failed at %g s)' % (kind, results['timeout']))
        bottom.set_ylabel('ms')
        bottom.set_yscale('log')
        plain_log_ticks(bottom, minor=True)     # 1000, 2000, not 10^3, 2x10^3
        for axis in (top, bottom):
            axis.set_xlabel('offered tasks per s (all robots)')
            axis.grid(True, alpha=0.3)
            legend_beside(axis)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def report(results, png):
    """The Markdown report (tables per task kind and the plot's link); writes the plot."""
    plot(results, png)
    text = ['# Capacity: %s' % results['scenario'], '',
            '%d robots, servers of %s of a core (cgroup quota) %s ms away (one way)%s, %g s '
            'measured per run, task timeout %g s (a failed task counts at it); median '
            '(min-max) of the runs.' % (
                results['robots'], ', '.join('%g' % s for s in results['shares']),
                ', '.join('%g' % d for d in results['delays']),
                ', the last one starting a third of the way in' if results['late'] else '',
                results['seconds'], results['timeout']), '']
    for kind, info in results['kinds'].items():
        text += ['## %s tasks: %.1f ms of CPU each (measured here on one core), capacity by '
                 'it %.2f tasks/s; the most the servers did: %s tasks/s' % (
                     kind, 1e3 * info['cpu_per_task'], info['capacity'],
                     '%.2f' % measured(info['runs']) if measured(info['runs']) else '-'), '',
                 'Offered load is in multiples of the capacity by CPU; "goodput / measured '
                 'capacity" is to the most work the servers were seen to do in any run.', '',
                 table(kind, info['runs'], info['capacity']), '']
    text.append('![goodput and round trip against offered load](%s)' % os.path.basename(png))
    return '\n'.join(text) + '\n'
