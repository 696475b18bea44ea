#!/usr/bin/env python3
"""Bad input: invalid parameters stop a node with one clear line; bad tasks get error
results and the server keeps serving."""

import concurrent.futures
import subprocess
import sys
import time
import unittest

import numpy as np
import rospy
import rostest
from rospy.numpy_msg import numpy_msg

from server_select.core.config import names
from server_select.core.util.procs import wait_until
from server_select.msg import SortResult, SortTask

from support.output import output_until
from support.record import until_answered

# One case per node: that a refused parameter ends the node with one clear line and exit
# status 2. Every parameter each node refuses, and why, is test/ros/test_node_params.py's.
BAD_PARAMS = [
    ('robot', ['_robot_id:=1', '_servers:=1,2,3', '_mode:=random'],
     "~mode: unknown mode 'random'"),
    ('manager', ['_robots:=1', '_servers:=1', '_window:=0'], '~window: expected a positive'),
    ('server', ['_server_id:=-3'], '~server_id: ids must be non-negative, got -3'),
]


class BadInputTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_bad_input')
        cls.results = []
        cls.sub = rospy.Subscriber(names.SORT_RESULT_TOPIC, numpy_msg(SortResult),
                                   lambda m: cls.results.append(m), tcp_nodelay=True)
        cls.pub = rospy.Publisher(names.SORT_TASK_TOPIC, numpy_msg(SortTask), queue_size=10)

    def test_invalid_parameters_exit_with_one_clear_line(self):
        procs = [subprocess.Popen(
            ['rosrun', 'server_select', node, '__name:=bad_%s_%d' % (node, i)] + args,
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
            for i, (node, args, _) in enumerate(BAD_PARAMS)]     # at once: each starts cold
        for proc, (node, args, message) in zip(procs, BAD_PARAMS):
            _, stderr = proc.communicate(timeout=60)
            lines = [x for x in stderr.splitlines() if 'invalid parameter' in x]
            self.assertEqual(proc.returncode, 2, (node, args, stderr))
            self.assertEqual(len(lines), 1, stderr)
            self.assertIn(message, lines[0])
            self.assertNotIn('Traceback', stderr)

    def roslaunch(self, until, *args):
        """Output of ``roslaunch server_select robot.launch ARGS`` until a line contains
        ``until`` (then it is stopped) or it ends by itself (within 30 s)."""
        return output_until(['roslaunch', 'server_select', 'robot.launch', 'output:=screen']
                            + list(args), until, 30.0)

    def test_launch_arguments_are_checked_by_the_node(self):
        with concurrent.futures.ThreadPoolExecutor(2) as launches:     # at once, as above
            # select mode with servers that do not include the (old) default fixed server 1
            good = launches.submit(self.roslaunch, 'probing servers', 'robot_id:=5',
                                   'servers:=2,3')
            bad = launches.submit(self.roslaunch, 'processing monitor complete', 'robot_id:=6',
                                  'servers:=1,2,3', 'task_rate:=fast')
        out = good.result()
        self.assertNotIn('invalid parameter', out)
        self.assertIn('robot 5: mode select, probing servers [2, 3]', out)
        out = bad.result()
        lines = [x for x in out.splitlines() if 'invalid parameter' in x]
        self.assertEqual(len(lines), 1, out)
        self.assertIn('~task_rate: expected a positive number', lines[0])
        self.assertIn("/robot6: the launch ends, this node's parameter being invalid", out)

    def send(self, task_id, data, server_id=1):
        task = SortTask(robot_id=77, task_id=task_id, server_id=server_id,
                        data=np.asarray(data, dtype=np.int32))
        task.header.stamp = rospy.Time.now()
        self.pub.publish(task)

    def result(self, task_id, timeout=5.0):
        def found():
            return [r for r in self.results if r.task_id == task_id]
        wait_until(found, timeout, period=0.02)
        return found()

    def test_bad_tasks_get_error_results_and_the_server_keeps_serving(self):
        self.assertTrue(until_answered(lambda: self.send(0, [2, 1]),
                                       lambda: any(r.task_id == 0 for r in self.results)),
                        'server 1 never answered')
        self.send(1, [])
        (empty,) = self.result(1)
        self.assertFalse(empty.ok)
        self.assertIn('empty task', empty.error)
        self.assertEqual((empty.robot_id, empty.server_id, len(empty.data)), (77, 1, 0))

        self.send(2, np.arange(1001)[::-1])  # the test launches the server with max 1000
        (oversized,) = self.result(2)
        self.assertFalse(oversized.ok)
        self.assertIn('exceeds max_task_len 1000', oversized.error)

        self.send(3, [5, -2, 9, 0])
        self.send(4, [1, 2], server_id=7)      # another server's task: not answered here
        (good,) = self.result(3)
        self.assertTrue(good.ok, good.error)
        self.assertEqual(list(good.data), [-2, 0, 5, 9])
        self.assertGreaterEqual(good.process_time, 0.0)
        time.sleep(0.5)
        self.assertEqual([r for r in self.results if r.task_id == 4], [])
        self.assertEqual(sorted(r.task_id for r in self.results if r.task_id), [1, 2, 3])


if __name__ == '__main__':
    rostest.rosrun('server_select', 'test_bad_input', BadInputTest, sys.argv)
