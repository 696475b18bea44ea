"""The soak's verdict and report: the invariants (:mod:`server_select.soak.checks`) over the
history of one soak folder, its fault timeline, recovery per fault kind, the nodes'
resource slopes, ``report.md`` and ``timeline.png`` (faults shaded, round trips, failures,
RSS per node)."""

import collections
import csv
import json
import os

from server_select.core.settings import default
from server_select.core.util.stats import percentile
from server_select.core.util.tables import markdown_table
from server_select.soak import checks, nemesis, resources
from server_select.soak.plan import ROBOTS

RSS_SLOPE_MAX = 1.0     # MiB per 10 minutes per node
COUNT_GROWTH_MAX = 1.0  # descriptors or threads per 10 minutes: no net growth
SLOPES_FROM = 20 * 60.0  # s: a shorter soak reports its slopes but is not judged on them
TASK_TIMEOUT = default('task_timeout')     # s: the soak's robots have the default


def _restarted(event):
    """Nodes a fault restarted (and must serve again)."""
    kind, target = event['kind'], event['target']
    if kind in ('server_kill', 'robot_kill'):
        return ['%s%d' % (kind.split('_')[0], target)]
    if kind == 'manager_kill':
        return ['manager']
    if kind == 'roscore_kill':
        return ['manager'] + ['robot%d' % r for r in ROBOTS]
    return []


def timeline(events, hist, t0):
    """One row per fault (its event, with ``serving``: how long after its window the nodes
    it restarted served again; ``recovery``: how long after that the fleet was back)."""
    rows = [dict(event, at=event['start'] - t0, lasted=event['end'] - event['start'],
                 serving=checks.served_again(event, hist, _restarted(event)))
            for event in events]
    for row in rows:
        over = checks.over_with(row, rows)      # the next fault after it ends the search
        limit = min([r['start'] for r in rows if r['start'] > over], default=over + 60)
        row['recovery'], row['reference'] = checks.recovery(hist.reports, row, rows,
                                                            set(ROBOTS), limit)
        late = row['recovery'] is None or row['recovery'] > row['bound']
        row['held back by'] = checks.held_back(
            hist.reports, row, rows, set(ROBOTS), limit) if late else []
    return rows


def _fmt(value, spec='%.1f'):
    return 'never' if value is None else spec % value


def analyse(folder, hist):
    """The verdict of the soak in ``folder`` (History ``hist``); writes report.md and the
    timeline plot. ``{'passed': bool, ...counts}``."""
    with open(os.path.join(folder, 'events.json')) as stream:
        log = json.load(stream)
    events, t0 = log['events'], log['t0']
    stops = [tuple(s) for s in log['stops']]
    samples = _samples(os.path.join(folder, 'resources.csv'))
    ledger = checks.ledger(hist.reports, hist.sent, stops, TASK_TIMEOUT)
    rows = timeline(events, hist, t0)
    stray = checks.stray_failures(hist.reports, rows, TASK_TIMEOUT, log['measured'])
    late = [r for r in rows if r['recovery'] is None or r['recovery'] > r['bound']]
    unnamed = [t for t, count in checks.intruders_named(hist.logs, rows) if not count]
    not_serving = [(r['kind'], n) for r in rows for n, s in r['serving'].items() if s is None]
    half = (t0 + log['duration'] / 2.0, t0 + log['duration'])
    slopes = resources.slopes(samples, *half)
    judged = log['duration'] >= SLOPES_FROM
    leaks = [(node, m) for node, per in slopes.items() for m, (slope, _) in per.items()
             if judged and node in nemesis.MAIN_NODES and m != 'cpu_s'   # the fleet's
             and slope > (RSS_SLOPE_MAX if m == 'rss_mib' else COUNT_GROWTH_MAX)]
    verdict = {'tasks': ledger['tasks'], 'reports': ledger['reports'],
               'unreported': len(ledger['unreported']),
               'duplicated': len(ledger['duplicated']),
               'lost with a killed robot': ledger['lost with a killed robot'],
               'failed outside faults': len(stray), 'late recoveries': len(late),
               'restarted nodes not serving': len(not_serving), 'leaks': len(leaks),
               'intruders not named': len(unnamed)}
    verdict['passed'] = not any(verdict[k] for k in (
        'unreported', 'duplicated', 'failed outside faults', 'late recoveries',
        'restarted nodes not serving', 'leaks', 'intruders not named'))
    quiet = checks.warnings_outside(hist.logs, rows, log['measured'])
    verdict['warnings outside faults'] = quiet
    text = _markdown(log, verdict, ledger, stray, rows, slopes, judged, hist)
    with open(os.path.join(folder, 'report.md'), 'w') as stream:
        stream.write(text)
    from server_select.soak import timeline_plot
    timeline_plot.draw(os.path.join(folder, 'timeline.png'), rows, hist, samples, t0)
    with open(os.path.join(folder, 'verdict.json'), 'w') as stream:
        json.dump(verdict, stream, indent=1)
    return verdict


def _samples(path):
    with open(path) as stream:
        rows = list(csv.DictReader(stream))
    return [resources.Sample(float(r['t']), r['node'], int(r['pid']), float(r['rss_mib']),
                             int(r['fds']), int(r['threads']), float(r['cpu_s'])) for r in rows]


def _markdown(log, verdict, ledger, stray, rows, slopes, judged, hist):
    t0 = log['t0']
    lines = ['# Soak: %.0f minutes, %d faults' % (log['duration'] / 60.0, len(rows)), '',
             '**%s.** %d tasks of %d robot lives, %d reports from %d bags.' % (
                 'Every invariant holds' if verdict['passed'] else 'An invariant FAILS',
                 ledger['tasks'], ledger['robot lives'], ledger['reports'], len(hist.bags)),
             '', '## Invariants', '']
    slope_note = '' if judged else ' (not judged: under 20 min)'
    checked = [('every task reported', 'unreported', 0),
               ('no task reported twice', 'duplicated', 0),
               ('failures only in a fault window + its recovery', 'failed outside faults', 0),
               ('the fleet back within the bound after each fault', 'late recoveries', 0),
               ('every restarted node serves again', 'restarted nodes not serving', 0),
               ('each keyless intruder named in a warning', 'intruders not named', 0),
               ('no resource slope over its target' + slope_note, 'leaks', 0)]
    lines.append(markdown_table(['invariant', 'count', 'verdict'], [
        [what, verdict[key], 'pass' if verdict[key] == want else 'FAIL']
        for what, key, want in checked]))
    lines += ['', 'Tasks lost with a robot killed while they were out (sent in its last '
              'task timeout): %d. Log lines at WARN or above outside faults: %s.' % (
                  ledger['lost with a killed robot'], ', '.join(
                      '%s %d' % item for item in sorted(
                          verdict['warnings outside faults'].items())) or 'none')]
    for label, items in (('unreported', ledger['unreported']),
                         ('duplicated', ledger['duplicated'])):
        if items:
            lines.append('First %s (robot, life, task): %s' % (label, items[:10]))
    if stray:
        lines.append('First failures outside faults (s, robot, task, error): %s' % [
            (round(r.t - t0, 1), r.robot, r.task, r.error) for r in stray[:10]])
    lines += ['', '## Faults', '', markdown_table(
        ['at s', 'kind', 'target', 'lasted s', 'back after s', 'bound s', 'served again s',
         'what', 'held back by'],
        [['%.1f' % r['at'], r['kind'], r['target'] or '', '%.1f' % r['lasted'],
          _fmt(r['recovery']), '%g' % r['bound'], _serving(r['serving']), r['detail'],
          _held(r['held back by'])] for r in rows])]
    lines += ['', '## Recovery by kind', '', markdown_table(
        ['kind', 'faults', 'median s', 'max s', 'bound s'], _by_kind(rows))]
    lines += ['', '## Resources over the second half (slope per 10 minutes)', '',
              markdown_table(['node', 'RSS MiB', 'descriptors', 'threads', 'CPU %', 'samples'],
                             [[node] + ['%+.2f' % per[m][0] if m in per else '-'
                                        for m in resources.MEASURES]
                              + [max(n for _, n in per.values())]
                              for node, per in sorted(slopes.items())]),
              '', 'Targets: RSS at most %+.1f MiB, descriptors and threads at most %+.1f per '
              '10 minutes per node.' % (RSS_SLOPE_MAX, COUNT_GROWTH_MAX),
              '', '![timeline](timeline.png)', '']
    return '\n'.join(lines)


def _held(pairs):
    """A late recovery's cause: e.g. 'robot 2 sort 3.4x on server 2; robot 6 image 2
    failed'."""
    return '; '.join('robot %d %s%s%s%s' % (
        robot, kind, ' %.1fx' % ratio if ratio is not None else '',
        ' %d failed' % failed if failed else '', ' on server %d' % server if server else '')
        for robot, kind, ratio, failed, server in pairs)


def _serving(serving):
    """When the restarted nodes served again: each (a few), or the last of many."""
    if len(serving) < 4:
        return ', '.join('%s %s' % (node, _fmt(s)) for node, s in sorted(serving.items()))
    if any(s is None for s in serving.values()):
        return 'some never'
    return 'all %s' % _fmt(max(serving.values()))


def _by_kind(rows):
    kinds = collections.OrderedDict()
    for row in rows:
        kinds.setdefault(row['kind'], []).append(row)
    out = []
    for kind, mine in kinds.items():
        backs = [r['recovery'] for r in mine]
        known = [b for b in backs if b is not None]
        out.append([kind, len(mine), _fmt(percentile(sorted(known), 50) if known else None),
                    _fmt(max(known) if len(known) == len(backs) else None),
                    '%g' % mine[0]['bound']])
    return out
