#!/usr/bin/env python3
"""The manager alone, fed synthetic samples: ranking, exclusion, change and staleness.

Runs against manager.launch with robots 1,2, servers 1,2,3, ``~window`` 2 s and a slow
periodic rate (0.1 Hz), so that any flag within a second of a change was sent because of
the change.
"""

import sys
import threading
import time
import unittest

import rospy
import rostest

from server_select.core.config import names
from server_select.msg import LatencySample

from support.record import FleetRecorder

WINDOW = 2.0
PUBLISH_RATE = 0.1
SETTLE = 1.0 / PUBLISH_RATE  # how long a state is awaited; how soon it came is asserted apart


class ManagerTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_manager')
        cls.rec = FleetRecorder()
        cls.pubs = dict(((r, s), rospy.Publisher(names.sample_topic(r, s), LatencySample,
                                                 queue_size=100))
                        for r in (1, 2) for s in (1, 2, 3))
        ok = cls.rec.wait_for(
            lambda: all(p.get_num_connections() > 0 for p in cls.pubs.values())
            and cls.rec.subs[0].get_num_connections() > 0, 20.0)
        assert ok, 'manager did not connect'

    def send(self, robot, server, rtt, claimed=None):
        sample = LatencySample(robot_id=robot, server_id=server, ok=rtt is not None,
                               rtt=rtt or 0.0)
        if claimed:
            sample.robot_id, sample.server_id = claimed
        sample.header.stamp = rospy.Time.now()
        self.pubs[(robot, server)].publish(sample)

    def feed(self, scenario, stop):
        """Send ``{(robot, server): rtt or None (failed)}`` at 10 Hz until ``stop`` is set."""
        while not stop.is_set() and not rospy.is_shutdown():
            for (robot, server), rtt in list(scenario.items()):
                self.send(robot, server, rtt)
            # samples on robot 1's topic that claim another pair must be ignored
            self.send(1, 1, 0.0001, claimed=(1, 3))
            self.send(1, 1, 0.0001, claimed=(9, 1))
            stop.wait(0.1)

    def flag_after(self, robot, since, condition, timeout):
        """The first flag of ``robot`` received after ``since`` meeting ``condition``."""
        def find():
            return next((r for r in self.rec.snapshot(self.rec.flags)
                         if r.time > since and r.msg.robot_id == robot and condition(r.msg)),
                        None)
        self.rec.wait_for(lambda: find() is not None, timeout)
        return find()

    def test_manager(self):
        scenario = {(1, 1): 0.010, (1, 2): 0.005, (1, 3): None, (2, 1): 0.001, (2, 3): 0.001}
        stop = threading.Event()
        feeder = threading.Thread(target=self.feed, args=(scenario, stop))
        start = time.monotonic()
        feeder.start()
        try:
            self.check_ranking_and_change(start, scenario)
        finally:
            stop.set()
            feeder.join()
        # without new samples everything goes stale: no server, all excluded
        last = time.monotonic()
        stale = self.flag_after(1, last, lambda f: f.server_id == -1, SETTLE)
        self.assertIsNotNone(stale, self.rec.latest_flags())
        self.assertEqual(list(stale.msg.excluded), [1, 2, 3])
        self.assertEqual(list(stale.msg.ranking), [])
        # sooner than the 10 s period: sent because the window emptied
        self.assertLessEqual(stale.time - last, WINDOW + 1.5)

    def check_ranking_and_change(self, start, scenario):
        flag = self.flag_after(1, start, lambda f: list(f.ranking) == [2, 1], SETTLE)
        self.assertIsNotNone(flag, self.rec.latest_flags())
        rospy.sleep(0.5)  # the window now holds several samples of each pair
        f = self.flag_after(1, time.monotonic(), lambda f: True, 1.0 / PUBLISH_RATE + 1.0).msg
        self.assertEqual((f.server_id, list(f.ranking), list(f.excluded)), (2, [2, 1], [3]))
        self.assertAlmostEqual(f.mean_latency[0], 0.005, places=9)
        self.assertAlmostEqual(f.mean_latency[1], 0.010, places=9)
        self.assertTrue(all(n >= 5 for n in f.sample_count), f.sample_count)

        f2 = self.rec.latest_flags()[2]
        # equal means: the lower id first (stable sort over ids in ascending order)
        self.assertEqual((f2.server_id, list(f2.ranking), list(f2.excluded)), (1, [1, 3], [2]))

        # a faster server for robot 2 is published at once, not at the 10 s period
        changed_at = time.monotonic()
        scenario[(2, 2)] = 0.0002
        f3 = self.flag_after(2, changed_at, lambda f: f.server_id == 2, SETTLE)
        self.assertIsNotNone(f3, 'no flag after the change')
        self.assertLess(f3.time - changed_at, 1.0)
        self.assertEqual(list(f3.msg.ranking), [2, 1, 3])


if __name__ == '__main__':
    rostest.rosrun('server_select', 'test_manager', ManagerTest, sys.argv)
