"""The soak's invariants over its whole history (pure: reports, rankings and flags from the
bags, faults from the nemesis's log).

- :func:`ledger`: every task of every life of every robot ends in exactly one report (a
  restarted robot counts its tasks from 1 again; a robot killed with tasks out loses those
  sent in its last task timeout, counted apart).
- :func:`stray_failures`: failed tasks sent outside every fault's window (from a task
  timeout before it starts to its recovery bound after it ends).
- :func:`recovery`: how long after a fault is over (its window ended, and the nodes it
  restarted serve again) the fleet is back: in a window of
  ``WINDOW`` s no task fails and the round trips are within ``TOLERANCE`` of the minute
  before the fault (each robot and kind against its own, so frames and sort tasks mix).
- :func:`held_back`: what kept a late recovery back (the robots and kinds slowed or
  failing, and the server that answered them).
- :func:`served_again`: how long after a fault a node it restarted does its job again.
"""

import bisect
import collections

WINDOW = 3.0        # s a recovered fleet must hold
STEP = 0.25         # s between the windows tried
TOLERANCE = 0.10    # the mean round trip at most this much above the pre-fault minute
REFERENCE = 60.0    # s before a fault that are its reference


def lives(stops):
    """{robot name: sorted [(time gone, time SIGKILLed or None)]} of the ends of robots'
    lives (a life's last task was sent before it was gone)."""
    ends = collections.defaultdict(list)
    for name, t, killed in stops:
        ends[name].append((t, killed))
    return dict((name, sorted(times)) for name, times in ends.items())


def life_of(ends, robot, t):
    """Which life of ``robot`` (0 first) sent a task at ``t``."""
    times = [e for e, _ in ends.get('robot%d' % robot, ())]
    return bisect.bisect_right(times, t)


def ledger(reports, sent, stops, timeout):
    """Counts over every robot's lives: tasks, reports, unreported, duplicated, and lost with
    a killed robot; and the lists of (robot, life, task) unreported and duplicated."""
    ends = lives(stops)
    copies = collections.defaultdict(collections.Counter)
    first_sent = {}
    for r in reports:
        copies[(r.robot, life_of(ends, r.robot, r.t))][r.task] += r.copies
    for s in sent:
        key = (s.robot, life_of(ends, s.robot, s.t), s.task)
        first_sent[key] = min(first_sent.get(key, s.t), s.t)
    highest = dict((key, max(tasks)) for key, tasks in copies.items())
    for robot, life, task in first_sent:
        highest[(robot, life)] = max(highest.get((robot, life), 0), task)
    result = {'robot lives': len(highest), 'tasks': 0, 'reports': 0, 'unreported': [],
              'duplicated': [], 'lost with a killed robot': 0}
    for (robot, life), top in sorted(highest.items()):
        seen = copies[(robot, life)]
        end = ends.get('robot%d' % robot, [])[life:life + 1]
        killed_at = end[0][1] if end else None
        settled = max([r.task for r in reports if r.robot == robot and killed_at is not None
                       and life_of(ends, robot, r.t) == life and r.t < killed_at - timeout],
                      default=0)
        result['tasks'] += top
        result['reports'] += sum(seen.values())
        for task in range(1, top + 1):
            if seen[task] > 1:
                result['duplicated'].append((robot, life, task))
            elif not seen[task]:
                if killed_at is not None and task > settled:
                    result['lost with a killed robot'] += 1
                else:
                    result['unreported'].append((robot, life, task))
    return result


def ready(event):
    """When a fault is over: the end of its window, or once the nodes it restarted serve
    again (``serving``: {node: s after the end}, None: never) if that is later."""
    late = [s for s in event.get('serving', {}).values() if s is not None]
    return event['end'] + max(late, default=0.0)


def over_with(event, events):
    """When ``event`` and every fault overlapping it, or one of those, are over (faults
    done at once, as in a wave of the short soak, are over together)."""
    over, changed = ready(event), True
    while changed:
        changed = False
        for other in events:
            if other['start'] <= over and ready(other) > over and \
                    ready(other) >= event['start']:
                over, changed = ready(other), True
    return over


def allowed(events, timeout):
    """The spans [start - timeout, ready + bound] in which a task may fail."""
    return [(e['start'] - timeout, ready(e) + e['bound']) for e in events]


def stray_failures(reports, events, timeout, measured):
    """Failed reports of tasks sent within ``measured`` (start, end) outside every fault's
    allowed span."""
    spans = allowed(events, timeout)
    return [r for r in reports if not r.ok and measured[0] <= r.t <= measured[1]
            and not any(a <= r.t <= b for a, b in spans)]


def _reference(reports, event, events, robots):
    """{(robot, kind): mean round trip} of the minute before ``event``, other faults'
    allowed spans left out."""
    spans = allowed(events, 0.0)
    sums = collections.defaultdict(list)
    for r in reports:
        if r.ok and r.robot in robots and event['start'] - REFERENCE <= r.t < event['start'] \
                and not any(a <= r.t <= b for a, b in spans):
            sums[(r.robot, r.kind)].append(r.rtt)
    return dict((key, sum(v) / len(v)) for key, v in sums.items() if len(v) >= 3)


def recovery(reports, event, events, robots, limit):
    """(s from when ``event`` and the faults overlapping it are over (:func:`over_with`)
    until the fleet is back, or None if not before ``limit``; the reference's size).
    Back: a window of WINDOW s from which every task of ``robots`` sent succeeded, with
    the mean of each round trip over its (robot, kind) reference at most 1 + TOLERANCE."""
    reference = _reference(reports, event, events, robots)
    over = over_with(event, events)
    mine = [r for r in reports if r.robot in robots and over <= r.t <= limit + WINDOW]
    stamps = [r.t for r in mine]
    t = over
    while t <= limit:
        inside = mine[bisect.bisect_left(stamps, t):bisect.bisect_right(stamps, t + WINDOW)]
        ratios = [r.rtt / reference[(r.robot, r.kind)] for r in inside
                  if r.ok and (r.robot, r.kind) in reference]
        if inside and all(r.ok for r in inside) and len(ratios) >= 5 and \
                sum(ratios) / len(ratios) <= 1.0 + TOLERANCE:
            return t - over, len(reference)
        t += STEP
    return None, len(reference)


def held_back(reports, event, events, robots, limit, most=3):
    """What kept the fleet from being back after ``event`` (a late recovery's cause, from
    the reports alone): the (robot, kind) pairs whose tasks sent from when it is over until
    ``limit`` failed, or took over 1 + TOLERANCE of their reference, worst first, at most
    ``most``, each as ``(robot, kind, mean over its reference or None, failed, the server
    that answered most of them or None)``."""
    reference = _reference(reports, event, events, robots)
    over = over_with(event, events)
    pairs = collections.defaultdict(list)
    for r in reports:
        if r.robot in robots and over <= r.t <= limit:
            pairs[(r.robot, r.kind)].append(r)
    found = []
    for (robot, kind), mine in pairs.items():
        answered = [r for r in mine if r.ok]
        failed = len(mine) - len(answered)
        ratio = sum(r.rtt for r in answered) / len(answered) / reference[(robot, kind)] \
            if answered and (robot, kind) in reference else None
        if failed or ratio is not None and ratio > 1.0 + TOLERANCE:
            servers = collections.Counter(r.answered_by for r in answered).most_common(1)
            found.append((robot, kind, ratio, failed, servers[0][0] if servers else None))
    return sorted(found, key=lambda f: (-f[3], -(f[2] or 0.0)))[:most]


def served_again(event, history, nodes):
    """{node: s from the end of ``event`` to its first sign of doing its job (None: none)}
    for ``nodes`` (a server in a robot's ranking with samples, a robot's answered task, the
    manager's flag)."""
    found = {}
    for node in nodes:
        if node.startswith('server'):
            server = int(node[6:])
            times = [r.t for r in history.rankings if r.t >= event['end'] and any(
                s == server and n > 0 for s, n in zip(r.ranking, r.counts))]
        elif node.startswith('robot'):
            times = [r.t for r in history.reports
                     if r.robot == int(node[5:]) and r.ok and r.t >= event['end']]
        else:
            times = [f.t for f in history.flags if f.sender == '/' + node
                     and f.t >= event['end']]
        found[node] = min(times) - event['end'] if times else None
    return found


WARN = 4        # rosgraph_msgs/Log.WARN


def warnings_outside(lines, events, measured):
    """{node: count} of log lines at WARN or above outside every fault's allowed span
    (a healthy fleet is quiet)."""
    spans = allowed(events, 0.0)
    found = collections.Counter()
    for line in lines:
        if line.level >= WARN and measured[0] <= line.t <= measured[1] and \
                not any(a <= line.t <= b for a, b in spans):
            found[line.node] += 1
    return dict(found)


def intruders_named(lines, events, name='/intruder'):
    """[(event start, warnings naming the intruder during its window and bound)] of each
    ``intruder`` fault: a refused keyless node is named in the fleet's logs."""
    out = []
    for event in (e for e in events if e['kind'] == 'intruder'):
        end = ready(event) + event['bound']
        out.append((event['start'], sum(1 for line in lines if line.level >= WARN and
                                        event['start'] <= line.t <= end and name in line.text)))
    return out
