"""Analysis of evaluation bags: tables and plots recomputed from the bags alone.

``load`` reads one bag with the rosbag API (times relative to the scenario's t0 from the
``<bag>.json`` written beside it); the other functions are pure and unit-tested.
"""

import collections
import json
import math
import os

from server_select.testbed.scenario import Scenario
from server_select.core.flow.outcome import cut_off
from server_select.core.observe.summary import switch_count
from server_select.core.settings import default
from server_select.core.util.stats import summarize
from server_select.core.util.tables import fmt, markdown_table

Flag = collections.namedtuple('Flag', 't robot server ranking means')
Report = collections.namedtuple('Report', 't robot task ok rtt server answered_by error attempts')
Report.__new__.__defaults__ = (1,)      # attempts: servers the task went to
Sample = collections.namedtuple('Sample', 't robot server ok rtt')
Run = collections.namedtuple('Run', 'meta flags reports samples servers')
Servers = collections.namedtuple('Servers', 't servers')


TOPICS = ('task_report', 'server_select_flag', 'latency_R<r>S<s>', 'latency_samples',
          'fleet_servers')


def load(bag_path):
    """A :class:`Run` from any bag holding the package's topics (found by their last name
    component, so namespaced or remapped recordings work too). Times are seconds since the
    scenario's t0 when the evaluation's ``<bag>.json`` is beside the bag, else since the
    bag's first message; ``meta`` is that JSON, or ``{}``."""
    import rosbag  # only here: the pure functions below need no ROS
    meta = {}
    if os.path.exists(bag_path + '.json'):
        with open(bag_path + '.json') as stream:
            meta = json.load(stream)
    flags, reports, samples, servers = [], [], [], []
    with rosbag.Bag(bag_path) as bag:
        t0 = meta.get('t0', bag.get_start_time() if bag.get_message_count() else 0.0)
        for topic, msg, stamp in bag.read_messages():
            t = stamp.to_sec() - t0
            name = topic.rsplit('/', 1)[-1]
            if name == 'server_select_flag':
                flags.append(Flag(t, msg.robot_id, msg.server_id, list(msg.ranking),
                                  list(msg.mean_latency)))
            elif name == 'task_report' and not cut_off(msg.error):
                reports.append(Report(t, msg.robot_id, msg.task_id, msg.ok, msg.rtt,
                                      msg.server_id, msg.answered_by, msg.error, msg.attempts))
            elif name.startswith('latency_R'):
                samples.append(Sample(t, msg.robot_id, msg.server_id, msg.ok, msg.rtt))
            elif name == 'latency_samples':     # the fleet profile's batch per probe round
                samples += [Sample(t, msg.robot_id, s, ok, rtt)
                            for s, ok, rtt in zip(msg.server_id, msg.ok, msg.rtt)]
            elif name == 'fleet_servers':
                servers.append(Servers(t, list(msg.servers)))
    return Run(meta, flags, reports, samples, servers)


def switches(reports):
    """Changes of the server a robot sent its tasks to (in task order), per robot.

    Counted from the robots' task reports, so that a fixed robot shows none whatever the
    manager publishes; tasks sent with no server selected do not count.
    """
    counts = collections.Counter()
    by_robot = collections.defaultdict(list)
    for r in reports:
        by_robot[r.robot].append((r.task, r.server))
    for robot, tasks in by_robot.items():
        counts[robot] = switch_count([server for _, server in sorted(tasks)])
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


def mode_summary(run_reports, flags, changes=None, timeout=default('task_timeout')):
    """The figures of one mode: task counts, round-trip statistics (a failed task counts
    at the task ``timeout``), switches, reactions."""
    rtt = summarize([r.rtt if r.ok else timeout for r in run_reports])
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


def _applies(summaries):
    """Which optional columns have a figure in some row: vs fixed (a fixed run), gap to
    oracle (an oracle run), reaction (a scenario)."""
    rows = summaries.values()
    return {'vs fixed': any(s.get('vs_fixed_pct') is not None for s in rows),
            'gap to oracle': any(s.get('gap_to_oracle_pct') is not None for s in rows),
            'reaction': any(s.get('reactions') for s in rows)}


def table(summaries, first='mode'):
    """Markdown table of :func:`mode_summary` results, one row per mode (or bag: the
    first column's heading is ``first``); the columns that apply to no row are left out
    (:func:`legend` says which and why)."""
    applies = _applies(summaries)
    rows = []
    for mode, s in summaries.items():
        r = s['rtt_ms']
        reaction = '-'
        if s.get('reactions'):
            reaction = '%s / %s (%d)' % (fmt(s['reaction_mean_s']), fmt(s['reaction_max_s']),
                                         s['reaction_missed'])
        rows.append([mode, s['tasks'], s['failed']]
                    + [fmt(r.get(k)) for k in ('mean', 'median', 'p95', 'p99', 'max')]
                    + [fmt(s.get('vs_fixed_pct'), '%+.1f %%')] * applies['vs fixed']
                    + [fmt(s.get('gap_to_oracle_pct'), '%+.1f %%')] * applies['gap to oracle']
                    + [s['switches']] + [reaction] * applies['reaction'])
    header = [first, 'tasks', 'failed', 'mean ms', 'median ms', 'p95 ms', 'p99 ms', 'max ms'] \
        + ['vs fixed'] * applies['vs fixed'] + ['gap to oracle'] * applies['gap to oracle'] \
        + ['switches'] + ['reaction mean / max s (missed)'] * applies['reaction']
    return markdown_table(header, rows)


LEGEND = (
    ('tasks, failed', "the robots' task reports, and those that got no right answer in time"),
    ('mean ... max ms', 'task round trip, each failed task counted at the task timeout'),
    ('vs fixed', "how much lower the mean is than the fixed server's (+: faster)"),
    ('gap to oracle', "how much higher the mean is than that of the oracle, which follows "
     'the truly nearest server of the scenario (+: slower)'),
    ('switches', 'changes of the server a robot sent its tasks to'),
    ('reaction', 'seconds from a change of the truly nearest server to the flag selecting it, '
     'mean / max (changes never followed)'),
)
WHY_LEFT_OUT = {'vs fixed': 'no fixed run to compare with',
                'gap to oracle': 'no oracle run to compare with',
                'reaction': 'no scenario, which says when the nearest server changes'}


def legend(summaries):
    """What the columns of :func:`table` mean, one line each, and which columns were left
    out, and why."""
    applies = _applies(summaries)
    lines = ['%s: %s' % (name, text) for name, text in LEGEND if applies.get(name, True)]
    left_out = [name for name in WHY_LEFT_OUT if not applies[name]]
    if left_out:
        lines.append('(left out: %s)' % '; '.join(
            '%s, %s' % (name, WHY_LEFT_OUT[name]) for name in left_out))
    return '\n'.join(lines)


def verdict(summaries, mode='select'):
    """One line of what ``mode`` achieved against the fixed server and the oracle (by mean
    task round trip, failed tasks counted at the timeout), and how many tasks failed."""
    s = summaries.get(mode)
    if s is None:
        return 'no %s run to judge' % mode
    parts = []
    if s.get('vs_fixed_pct') is not None:
        parts.append('%.0f %% %s than a fixed server' % (
            abs(s['vs_fixed_pct']), 'faster' if s['vs_fixed_pct'] >= 0 else 'slower'))
    if s.get('gap_to_oracle_pct') is not None:
        parts.append('%.0f %% %s than the oracle that knows the network' % (
            abs(s['gap_to_oracle_pct']), 'slower' if s['gap_to_oracle_pct'] >= 0 else 'faster'))
    judged = ('%s was %s (mean task round trip); ' % (mode, ' and '.join(parts))) if parts \
        else '%s: nothing to compare with; ' % mode
    return judged + '%d of %d tasks failed.' % (s['failed'], s['tasks'])


def summarize_runs(runs, scenario=None, duration=None):
    """:func:`mode_summary` of each run (``{name: Run}``), compared; with a scenario, the
    reactions to its changes of the truly nearest server (fixed mode has none). Failed
    tasks count at the run's task timeout (the evaluation's metadata, else the default)."""
    changes = None
    if scenario is not None:
        robots = [h.id for h in scenario.of_role('robot')]
        changes = oracle_changes(scenario, robots, 0.0, duration or scenario.duration)
    return compare(collections.OrderedDict(
        (name, mode_summary(run.reports, run.flags, changes if name != 'fixed' else None,
                            run.meta.get('options', {}).get('task_timeout',
                                                            default('task_timeout'))))
        for name, run in runs.items()))


def write_report(runs, summaries, out_dir, title, description):
    """report.md, summary.json and the plots of ``runs`` in ``out_dir``; returns the text."""
    from server_select.testbed.plots import plot_latency, plot_task_rtt
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, 'summary.json'), 'w') as stream:
        json.dump(summaries, stream, indent=1)
    plot_task_rtt(runs, os.path.join(out_dir, 'task_rtt.png'))
    for name, run in runs.items():
        plot_latency(run, os.path.join(out_dir, 'latency_%s.png' % name), name)
    text = ['# %s' % title, '', description, '', table(summaries), '',
            '![task round trip](task_rtt.png)', '']
    text += ['![latency %s](latency_%s.png)' % (m, m) for m in runs]
    report = '\n'.join(text) + '\n'
    with open(os.path.join(out_dir, 'report.md'), 'w') as stream:
        stream.write(report)
    return report


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
    summaries = summarize_runs(runs, scenario, meta['duration'])
    return write_report(
        runs, summaries, out_dir, 'Evaluation: %s' % scenario.name,
        'Scenario `%s`, %.0f s per mode; task round trip from the robots\' `task_report`, a '
        'failed task counted at the task timeout; improvement and gap by mean round trip; '
        'reaction: from a change of the truly nearest server to the flag selecting it.'
        % (os.path.basename(meta['scenario']), meta['duration']))
