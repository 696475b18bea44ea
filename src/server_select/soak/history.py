"""The soak's history from its bags: task reports, robots' rankings, flags, tasks sent and
the nodes' log lines, each once however many recorders heard it.

A roscore restart gives the soak a new recorder (``rosbag record`` does not register again),
and the old one still hears the nodes it was connected to: a message may be in two bags.
Within one bag every publication is one record, so a message's copies are the most any
one bag holds of it; two copies in one bag are two publications (a duplicate).
"""

import collections
import glob
import os

from server_select.ros import bags

Report = collections.namedtuple('Report', 't robot task kind ok error rtt server answered_by '
                                'copies')
Ranking = collections.namedtuple('Ranking', 't robot ranking counts')
Flag = collections.namedtuple('Flag', 't robot server sender')
Sent = collections.namedtuple('Sent', 't robot task server sender')
Line = collections.namedtuple('Line', 't node level text')
History = collections.namedtuple('History', 'reports rankings flags sent logs bags')
KINDS = ('task_report', 'robot_rankings', 'server_select_flag', 'data', 'rosout')


def _stamp(msg):
    return msg.header.stamp.to_sec()


def _of_bag(path):
    """{kind: Counter of records} of one bag."""
    found = collections.defaultdict(collections.Counter)
    for kind, msg, _t, sender in bags.read(path, KINDS):
        if kind == 'task_report':
            found['reports'][(_stamp(msg), msg.robot_id, msg.task_id, msg.kind, msg.ok,
                              msg.error, repr(msg.rtt), msg.server_id, msg.answered_by)] += 1
        elif kind == 'robot_rankings':
            found['rankings'][(_stamp(msg), msg.robot_id, tuple(msg.ranking),
                               tuple(msg.sample_count))] += 1
        elif kind == 'server_select_flag':
            found['flags'][(_stamp(msg), msg.robot_id, msg.server_id, sender)] += 1
        elif kind == 'data':
            found['sent'][(_stamp(msg), msg.robot_id, msg.task_id, msg.server_id, sender)] += 1
        else:
            found['logs'][(_stamp(msg), msg.name, msg.level, msg.msg)] += 1
    return found


def merge(per_bag):
    """{kind: {record: copies}}: each record's copies the most one bag holds."""
    merged = collections.defaultdict(dict)
    for found in per_bag:
        for kind, records in found.items():
            for record, count in records.items():
                merged[kind][record] = max(merged[kind].get(record, 0), count)
    return merged


def own_sends(sent):
    """The tasks robots sent themselves, in time order: a task under a robot's id from
    another node (a keyless intruder's) is no task of that robot."""
    return sorted(s for s in sent if s.sender == '/robot%d' % s.robot)


def load(folder):
    """The History of the soak whose bags (``soak_<n>.bag``) are in ``folder``."""
    bags = sorted(glob.glob(os.path.join(folder, 'soak_*.bag')))
    merged = merge(_of_bag(path) for path in bags)
    reports = [Report(*(record + (copies,))) for record, copies in
               merged['reports'].items()]
    reports = [r._replace(rtt=float(r.rtt)) for r in reports]
    return History(sorted(reports), sorted(Ranking(*r) for r in merged['rankings']),
                   sorted(Flag(*r) for r in merged['flags']),
                   own_sends(Sent(*r) for r in merged['sent']),
                   sorted(Line(*r) for r in merged['logs']), bags)
