"""Every switch of a recorded run with its reason: where a robot's tasks went next, when,
and why (no rospy).

A switch is a change of the server a robot's tasks are first sent to (its task reports, in
task order: what the robot did, whatever was published); its reason is that of the newest
flag naming the new server for that robot since its previous switch, published no later
than ``AFTER`` s after the move (a robot that chooses per task puts its own words in its
ranking, and its manager's flag carries them). A switch with no such flag says so.
"""

import bisect
import collections

from server_select.core.util.tables import markdown_table

AFTER = 1.0         # s a flag may follow the first task it explains (the view's delay)
Switch = collections.namedtuple('Switch', 't robot before after reason')


def switches(reports, flags):
    """``[Switch]`` of a run's :class:`Report` and :class:`Flag` records, by time."""
    found = []
    by_robot = collections.defaultdict(list)
    for r in reports:
        if r.server is not None and r.server >= 0:
            by_robot[r.robot].append(r)
    named = collections.defaultdict(list)       # (robot, server) -> flags naming it
    for f in sorted(flags, key=lambda f: f.t):
        named[(f.robot, f.server)].append(f)
    for robot, tasks in by_robot.items():
        tasks.sort(key=lambda r: r.task)
        since = float('-inf')       # the robot's previous switch: older flags explain others
        for before, after in zip(tasks, tasks[1:]):
            if after.server != before.server:
                found.append(Switch(after.t, robot, before.server, after.server,
                                    _reason(named[(robot, after.server)], since, after.t)))
                since = after.t
    return sorted(found)


def _reason(flags, since, t):
    times = [f.t for f in flags]
    i = bisect.bisect_right(times, t + AFTER)
    if not i or flags[i - 1].t <= since:
        return '(no flag named it)'
    return flags[i - 1].reason or '(the flag gives none)'


def table(found, limit=None):
    """The switches as a Markdown table (time, robot, from, to, reason); the first
    ``limit`` with a line saying how many more."""
    shown = found if limit is None else found[:limit]
    text = markdown_table(['time s', 'robot', 'from', 'to', 'reason'],
                          [['%.1f' % s.t, s.robot, s.before, s.after, s.reason.replace(
                              '|', '/')] for s in shown])
    if len(found) > len(shown):
        text += '\n\n%d more switches in report.md' % (len(found) - len(shown))
    return text
