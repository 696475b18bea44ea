#!/usr/bin/env python3
"""TimedServiceProxy: every call ends by its deadline, and the proxy recovers afterwards.

- a server stopped with SIGSTOP (hung: the connection stays open, nothing answers);
- answers racing the deadline (a handler in this process that sleeps about as long as the
  deadline): each call either returns within its deadline or raises ProbeTimeout;
- a server killed with SIGKILL and started again: the proxy reconnects by itself.
"""

import os
import signal
import subprocess
import sys
import time
import unittest

import rospy
import rostest

from server_select.core.config import names
from server_select.core.util.procs import stop_group, stopped, wait_until
from server_select.ros.graph import node_pid
from server_select.ros.probe_client import ProbeTimeout, TimedServiceProxy
from server_select.srv import LatencyProbe, LatencyProbeRequest, LatencyProbeResponse

DEADLINE = 0.3
# how late a call that ended at its deadline may return: make test runs the rostests at nice
# 19 beside other tests, where a woken thread waited 0.44 s for the CPU (a hung call, without
# the deadline, would never return)
SLACK = 0.6
# a call after a timeout connects again, and asks the master where the service is first,
# within the call's deadline (before, that lookup had none: at nice 19 beside the other
# streams the master took up to about 1.1 s to answer, and call 3 ended after 1.44 s)


def request(seq):
    return LatencyProbeRequest(robot_id=7, seq=seq, stamp=rospy.Time.now())


def timed(proxy, seq, timeout=DEADLINE):
    """(outcome, seconds): the response, or the exception the call raised."""
    start = time.monotonic()
    try:
        outcome = proxy.call_within(request(seq), timeout)[0]
    except rospy.ServiceException as error:
        outcome = error
    return outcome, time.monotonic() - start


class ProbeClientTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_probe_client')
        rospy.wait_for_service(names.probe_service(1), 20.0)
        cls.proxy = TimedServiceProxy(names.probe_service(1), LatencyProbe)

    def answers(self, seq):
        response, elapsed = timed(self.proxy, seq, timeout=2.0)
        self.assertIsInstance(response, LatencyProbeResponse, response)
        self.assertEqual((response.server_id, response.seq), (1, seq))
        return elapsed

    def test_1_hung_server_times_out_then_recovers(self):
        self.answers(1)
        pid = node_pid('/server1', rospy.get_name())
        os.kill(pid, signal.SIGSTOP)
        try:
            self.assertTrue(wait_until(lambda: stopped(pid), 5.0), 'server1 did not stop')
            for seq in range(2, 5):
                outcome, elapsed = timed(self.proxy, seq)
                self.assertIsInstance(outcome, ProbeTimeout)
                limit = DEADLINE + SLACK
                self.assertLess(elapsed, limit, 'call %d took %.3f s' % (seq, elapsed))
        finally:
            os.kill(pid, signal.SIGCONT)
        self.answers(5)
        print('hung server: 3 of 3 calls ended by the deadline; answered again after SIGCONT')

    def test_2_answers_racing_the_deadline(self):
        delay = {'s': 0.0}

        def slow(req):
            time.sleep(delay['s'])
            return LatencyProbeResponse(server_id=99, seq=req.seq, stamp=req.stamp)
        rospy.Service('race_probe', LatencyProbe, slow)
        proxy = TimedServiceProxy('race_probe', LatencyProbe)
        outcomes = {'answered': 0, 'timed out': 0}
        for i in range(30):
            delay['s'] = 0.05 + 0.01 * (i % 10)          # 50-140 ms around a 100 ms deadline
            outcome, elapsed = timed(proxy, i, timeout=0.1)
            if isinstance(outcome, LatencyProbeResponse):
                outcomes['answered'] += 1
                self.assertEqual(outcome.seq, i)
                self.assertLess(elapsed, 0.1 + SLACK)
            else:
                self.assertIsInstance(outcome, ProbeTimeout, outcome)
                outcomes['timed out'] += 1
                self.assertLess(elapsed, 0.1 + SLACK)
            delay['s'] = 0.0
            # whatever happened, the next call with room to spare is answered, in order
            answer, _ = timed(proxy, 1000 + i, timeout=2.0)
            self.assertIsInstance(answer, LatencyProbeResponse, answer)
            self.assertEqual(answer.seq, 1000 + i)
        print('racing the deadline: %s' % outcomes)
        self.assertGreater(outcomes['answered'], 0)
        self.assertGreater(outcomes['timed out'], 0)

    def test_3_killed_server_fails_fast_and_a_restarted_one_is_found(self):
        self.answers(10)
        os.kill(node_pid('/server1', rospy.get_name()), signal.SIGKILL)
        outcome, elapsed = timed(self.proxy, 11)
        self.assertIsInstance(outcome, rospy.ServiceException)
        self.assertLess(elapsed, DEADLINE + SLACK)
        restarted = subprocess.Popen(['rosrun', 'server_select', 'server', '_server_id:=1',
                                      '__name:=server1'], start_new_session=True,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            self.assertTrue(wait_until(
                lambda: isinstance(timed(self.proxy, 12)[0], LatencyProbeResponse), 30.0,
                period=0.2), 'the restarted server was never reached')
            self.answers(13)
        finally:
            stop_group(restarted)
        print('killed server: failed in %.3f s; the restarted one answered' % elapsed)


if __name__ == '__main__':
    rostest.rosrun('server_select', 'test_probe_client', ProbeClientTest, sys.argv)
