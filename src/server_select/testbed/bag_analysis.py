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
from server_select.testbed import switch_table
from server_select.testbed.bag_tables import compare, table

Flag = collections.namedtuple('Flag', 't robot server ranking means reason')
Flag.__new__.__defaults__ = ('',)       # reason: why (bags of older versions: none)
Report = collections.namedtuple('Report',
                                't robot task ok rtt server answered_by error attempts kind')
Report.__new__.__defaults__ = (1, 'sort')   # attempts: servers the task went to; its kind
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
    from server_select.ros import bags  # only here: the pure functions below need no ROS
    meta = {}
    if os.path.exists(bag_path + '.json'):
        with open(bag_path + '.json') as stream:
            meta = json.load(stream)
    flags, reports, samples, servers = [], [], [], []
    t0 = meta.get('t0')
    for name, msg, stamp, _sender in bags.read(bag_path):
        t0 = stamp if t0 is None else t0        # (no metadata: since the first message)
        t = stamp - t0
        if name == 'server_select_flag':
            flags.append(Flag(t, msg.robot_id, msg.server_id, list(msg.ranking),
                              list(msg.mean_latency), getattr(msg, 'reason', '')))
        elif name == 'task_report' and not cut_off(msg.error):
            reports.append(Report(t, msg.robot_id, msg.task_id, msg.ok, msg.rtt, msg.server_id,
                                  msg.answered_by, msg.error, msg.attempts, msg.kind))
        elif name == bags.PAIR:
            samples.append(Sample(t, msg.robot_id, msg.server_id, msg.ok, msg.rtt))
        elif name == 'latency_samples':     # the fleet profile's batch per probe round
            samples += [Sample(t, msg.robot_id, s, ok, rtt)
                        for s, ok, rtt in zip(msg.server_id, msg.ok, msg.rtt)]
        elif name == 'fleet_servers':
            servers.append(Servers(t, list(msg.servers)))
    return Run(meta, flags, reports, samples, servers)


def switches(reports):
    """Changes of the server a robot sent its tasks to (in task order, within each kind),
    per robot.

    Counted from the robots' task reports, so that a fixed robot shows none whatever the
    manager publishes; tasks sent with no server selected do not count.
    """
    counts = collections.Counter()
    by_robot = collections.defaultdict(list)
    for r in reports:
        by_robot[r.robot].append((r.task, r.server, r.kind))
    for robot, tasks in by_robot.items():
        tasks.sort()
        counts[robot] = switch_count([s for _, s, _ in tasks], [k for _, _, k in tasks])
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


def felt_changes(scenario, changes, step=0.05, gap=1.0):
    """The changes of :func:`oracle_changes` from when a task would feel them: the first
    moment the previous nearest server is ``gap`` ms of round trip slower than the new one
    (or down). A step is felt at once; where two ramps cross, the servers are equal at the
    crossing and no measurement can tell them apart until the gap has grown. A change the
    robot's next one comes before it is felt is left out."""
    felt = []
    for i, (t, robot, new) in enumerate(changes):
        old = scenario.nearest_server(robot, t - step)
        following = [c[0] for c in changes[i + 1:] if c[1] == robot]
        limit = following[0] if following else scenario.duration
        u = t
        while u < limit:
            ranked, _ = scenario.ranking(robot, u)
            delays = dict((server, delay) for delay, server in ranked)
            if old not in delays or (new in delays and
                                     2.0 * (delays[old] - delays[new]) >= gap):
                felt.append((u, robot, new))
                break
            u += step
    return felt


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
    for name, run in runs.items():
        found = switch_table.switches(run.reports, run.flags)
        text += ['', '## Switches: %s' % name, '', 'Where a robot\'s tasks went next, and why '
                 '(the reason of the flag that named the new server).', '',
                 switch_table.table(found) if found else 'None.']
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
