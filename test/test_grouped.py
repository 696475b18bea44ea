#!/usr/bin/env python3
"""A grouped deployment (grouped_example.launch): assignment, probing and flags per group.

Robots start knowing no server. The top manager must put each robot in a group; the robot
must then probe exactly its group's servers plus every group's representative, take flags
only from its group's manager (whose rankings hold only that group's servers), and have
its tasks answered.
"""

import sys
import unittest

import rospy
import rostest

from server_select.core.config import names
from server_select.core.fleet.groups import probe_set
from server_select.core.util.procs import wait_until
from server_select.msg import GroupAssignments, LatencySamples, SelectionFlag, TaskReport
from server_select.ros.graph import publisher_of

from support.record import Topics

ROBOTS = (1, 2)


class GroupedTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_grouped')
        cls.got = Topics({'tables': (names.GROUPS_TOPIC, GroupAssignments),
                          'batches': (names.SAMPLES_TOPIC, LatencySamples),
                          'flags': (names.SELECTION_TOPIC, SelectionFlag),
                          'reports': (names.TASK_REPORT_TOPIC, TaskReport)}, clock=rospy.get_time)

    def table(self):
        """The last assignment table: ({group: servers}, {robot: group}, ROS time received),
        or None."""
        tables = self.got.received('tables')
        if not tables:
            return None
        t, msg = tables[-1]
        return (dict((g.group_id, list(g.servers)) for g in msg.groups),
                dict(zip(msg.robot_id, msg.group_id)), t)

    def snapshot(self, store):
        """(ROS time received, sender, message) of each message of ``store``."""
        return [(t, publisher_of(m), m) for t, m in self.got.received(store)]

    def test_robots_are_grouped_probe_their_group_and_follow_its_manager(self):
        self.assertTrue(wait_until(lambda: self.table() and all(
            r in self.table()[1] for r in ROBOTS), 30.0), 'assignments: %s' % (self.table(),))
        self.assertTrue(wait_until(lambda: all(
            sum(1 for _, _, m in self.snapshot('reports') if m.robot_id == r) >= 20
            for r in ROBOTS), 60.0))

        def settled():
            """Every robot has probed all of its probe set, been flagged and had a task
            answered since 2 s after the last table (robots that choose per task start
            sending before that: wait for the state, not for a count of tasks)."""
            groups, assigned, since = self.table()
            for robot in ROBOTS:
                after = since + 2.0
                probed = set().union(*([set(m.server_id) for t, _, m in
                                        self.snapshot('batches')
                                        if m.robot_id == robot and t > after] or [set()]))
                if not probed >= set(probe_set(groups, assigned[robot])) or not any(
                        m.robot_id == robot and t > after for t, _, m in self.snapshot('flags')) \
                        or not any(m.robot_id == robot and m.ok and m.header.stamp.to_sec() > after
                                   for _, _, m in self.snapshot('reports')):
                    return False
            return True
        self.assertTrue(wait_until(settled, 30.0), 'table %s' % (self.table(),))
        groups, assigned, since = self.table()
        reports = [m for _, _, m in self.snapshot('reports')]
        self.assertEqual([(m.robot_id, m.task_id, m.error) for m in reports if not m.ok], [])
        for robot in ROBOTS:
            group = assigned[robot]
            late = [m for t, _, m in self.snapshot('batches')
                    if m.robot_id == robot and t > since + 2.0]
            self.assertTrue(late)
            # rounds are uneven (adaptive probing: contenders every round, the others
            # now and then): together they probe the group's servers and no other
            self.assertEqual(set().union(*(m.server_id for m in late)),
                             set(probe_set(groups, group)))
            # a robot may have been in another group before the last table (the top
            # manager moves it as its probes come in): that group's manager flagged it then
            flags = [(sender, m) for t, sender, m in self.snapshot('flags')
                     if m.robot_id == robot and t > since + 2.0]
            self.assertTrue(flags)
            self.assertEqual(set(sender for sender, _ in flags), {'/manager_g%d' % group})
            self.assertTrue(all(set(m.ranking) <= set(groups[group]) for _, m in flags))
            # once the robot follows its group (its first task answered there after the
            # table: the robot hears the table when it does, later than this test on a
            # loaded host), every task of it is answered there
            mine = sorted((m.header.stamp.to_sec(), m.answered_by) for m in reports
                          if m.robot_id == robot and m.header.stamp.to_sec() > since)
            first = next((t for t, server in mine if server in groups[group]), None)
            self.assertIsNotNone(first, mine)
            answered = set(server for t, server in mine if t >= first)
            self.assertTrue(answered <= set(groups[group]), answered)


if __name__ == '__main__':
    rostest.rosrun('server_select', 'test_grouped', GroupedTest, sys.argv)
