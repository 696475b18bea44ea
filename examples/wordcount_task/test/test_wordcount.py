#!/usr/bin/env python3
"""wordcount.test: the example task type, built in a workspace of its own, goes the way of
the built-in ones: the selected server answers, the robot checks, one task_report each."""

import sys
import threading
import unittest

import rospy
import rostest

from server_select.core.util.procs import wait_until
from server_select.msg import TaskReport
from wordcount_task.msg import WordCountResult


class WordCountTest(unittest.TestCase):

    def test_word_count_tasks_are_answered_by_the_servers(self):
        rospy.init_node('test_wordcount')
        lock, reports, results = threading.Lock(), [], []

        def keep(store):
            def add(msg):
                with lock:
                    store.append(msg)
            return add
        rospy.Subscriber('/task_report', TaskReport, keep(reports))
        rospy.Subscriber('/processed_wordcount', WordCountResult, keep(results))
        wait_until(lambda: sum(r.ok for r in reports) >= 10, 40.0)
        with lock:
            reports, results = list(reports), list(results)
        self.assertGreaterEqual(sum(r.ok for r in reports), 10, reports[-3:])
        self.assertEqual(set(r.kind for r in reports), {'wordcount'})
        self.assertEqual([r.error for r in reports if not r.ok], [])
        ids = sorted(r.task_id for r in reports)
        self.assertEqual(ids, list(range(1, len(ids) + 1)))       # each task reported once
        self.assertTrue(all(r.answered_by in (1, 2) for r in reports))
        # "the quick brown fox jumps over the lazy dog <id>": 10 words
        self.assertEqual(set(r.words for r in results if r.ok), {10})


if __name__ == '__main__':
    rostest.rosrun('wordcount_task', 'test_wordcount', WordCountTest, sys.argv)
