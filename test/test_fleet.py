#!/usr/bin/env python3
"""Integration test of a running fleet (demo.launch): selection, probing, task delivery.

Parameters (private): ``robots``, ``servers`` (id lists), ``tasks`` (per robot), ``mode``
(``select`` or ``fixed``), ``fixed_server``, ``timeout`` (s to wait for all tasks),
``routing`` (``broadcast`` or ``direct``: the fleet profile), ``best_first`` (default true:
the flag selects its ranking's first; false for a policy with a margin, which may keep a
server the ranking no longer puts first), ``chooses`` (default false: robots follow the
flags; true: robots choose per task, as the fleet profile's do, and the flags follow them).
"""

import collections
import re
import subprocess
import sys
import threading
import unittest

import rosgraph
import rosnode
import rospy
import rostest
from rosgraph_msgs.msg import Log

from server_select.core.config import names
from server_select.core.config.params import parse_id_list
from server_select.msg import SelectionFlag

from support.record import FleetRecorder, until_answered


NO_SERVER = 'no server selected'     # the report's error when no server may be used
MAX_UNSERVED = 2     # tasks a robot may fail that way (start-up on a loaded machine)


class FleetTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_fleet')
        cls.robots = parse_id_list('robots', rospy.get_param('~robots'))
        cls.servers = parse_id_list('servers', rospy.get_param('~servers'))
        cls.tasks = int(rospy.get_param('~tasks'))
        cls.mode = rospy.get_param('~mode', 'select')
        cls.fixed_server = int(rospy.get_param('~fixed_server', 1))
        cls.timeout = float(rospy.get_param('~timeout', 60.0))
        cls.direct = rospy.get_param('~routing', 'broadcast') == 'direct'
        cls.best_first = bool(rospy.get_param('~best_first', True))
        cls.chooses = bool(rospy.get_param('~chooses', False))
        cls.rec = FleetRecorder(cls.robots, cls.servers) if cls.direct else FleetRecorder()
        cls.logs, cls.log_lock = [], threading.Lock()
        rospy.Subscriber('/rosout', Log, cls.on_log, queue_size=1000)

    def test_every_robot_selects_a_live_server(self):
        if self.mode == 'fixed':   # no manager runs: no flag names a server the robots do not use
            self.assertTrue(self.rec.wait_for(lambda: all(
                len(self.rec.reports_of(r)) >= 5 for r in self.robots), 20.0))
            self.assertEqual(self.rec.snapshot(self.rec.flags), [])
            served = set(r.answered_by for robot in self.robots
                         for r in self.rec.reports_of(robot) if r.ok)
            self.assertEqual(served, {self.fixed_server})
            return

        def all_selected():
            flags = self.rec.latest_flags()
            return all(r in flags and flags[r].server_id in self.servers for r in self.robots)
        self.assertTrue(self.rec.wait_for(all_selected, 20.0),
                        'flags received: %s' % self.rec.latest_flags())
        for robot, flag in self.rec.latest_flags().items():
            self.assertIn(robot, self.robots)
            self.assertIn(flag.server_id, flag.ranking)
            if self.best_first:
                self.assertEqual(flag.ranking[0], flag.server_id)
            self.assertEqual(len(flag.ranking), len(flag.mean_latency))
            # ascending; a robot that chooses per task puts where its tasks go first
            rest = list(flag.mean_latency[1:]) if flag.ranking[0] == flag.server_id and \
                flag.reason else list(flag.mean_latency)
            self.assertEqual(rest, sorted(rest), (flag.ranking, flag.mean_latency, flag.reason))
            self.assertTrue(all(0 < m < 1.0 for m in flag.mean_latency), flag.mean_latency)

    def test_each_robot_hears_its_flags_where_its_profile_says(self):
        """Fleet profile: the manager sends robot r's flags on robot_<r>/server_select_flag,
        latched, and no robot listens on the shared topic (only recorders do). Paper
        profile: every robot listens on the shared topic, which the manager publishes, and
        no robot topic exists. Fixed mode: no node publishes any flag."""
        master = rosgraph.Master(rospy.get_name())
        own = ['/' + names.robot_topic(r, names.SELECTION_TOPIC) for r in self.robots]
        shared_topic = '/' + names.SELECTION_TOPIC
        if self.mode == 'fixed' or not self.direct:
            # every robot's: one that started later may not listen yet when another has
            # (a paper robot's tasks follow its first flag)
            self.assertTrue(self.rec.wait_for(lambda: all(len(self.rec.reports_of(r)) >= 3
                                                          for r in self.robots), 30.0),
                            'no task reports')
            pubs, subs = (dict(x) for x in master.getSystemState()[:2])
            self.assertEqual([t for t in own if t in pubs], [], pubs)
            flaggers = pubs.get(shared_topic, [])
            self.assertEqual(flaggers, [] if self.mode == 'fixed' else ['/manager'])
            robot_nodes = [n for n in rosnode.get_node_names() if '/robot' in n]
            self.assertEqual(len(robot_nodes), len(self.robots), robot_nodes)
            self.assertLessEqual(set(robot_nodes), set(subs.get(shared_topic, ())), subs)
            print('flags: %s; the robots %s listen on the shared topic' % (
                'no node publishes one (fixed mode)' if self.mode == 'fixed'
                else 'the manager publishes the shared topic', robot_nodes))
            return
        # the manager flags a robot once it has heard the robot's samples: on a loaded
        # host (catkin's run beside the other test streams) the fleet's start alone once
        # took longer than the 20 s the latched delivery below is given (its copy on the
        # shared topic, which the recorder hears, says it happened)
        self.assertTrue(self.rec.wait_for(
            lambda: set(self.robots) <= set(self.rec.latest_flags()), 60.0),
            'the manager flagged no robot of %s in 60 s' % self.robots)
        listeners = {}
        for robot, topic in zip(self.robots, own):
            got, handles = [], []

            def listen():
                # latched: at once; but a subscriber whose connection is lost as it is made
                # never connects again (rospy; once in CI under load: no flag in 20 s), so
                # it is made anew every 5 s (its old topic closed first: a second handle
                # would share the unconnected one)
                for handle in handles:
                    handle.unregister()
                handles[:] = [rospy.Subscriber(topic, SelectionFlag, got.append)]
            self.assertTrue(until_answered(listen, lambda: got, timeout=20.0, period=5.0),
                            'no flag on %s' % topic)
            for handle in handles:
                handle.unregister()
            self.assertEqual(set(f.robot_id for f in got), {robot}, topic)
            pubs, subs, _ = master.getSystemState()
            self.assertEqual(dict(pubs).get(topic), ['/manager'], topic)
            listeners[robot] = set(dict(subs).get(topic, ())) - {rospy.get_name()}
            self.assertEqual(len(listeners[robot]), 1, (topic, listeners[robot]))
        shared = set(dict(master.getSystemState()[1]).get(shared_topic, ()))
        robot_nodes = set.union(*listeners.values())
        self.assertEqual(len(robot_nodes), len(self.robots), listeners)
        self.assertEqual(shared & robot_nodes, set(), shared)
        print('flags: each robot listens on its own topic only (%s); the shared topic has '
              '%d listener(s), no robot' % (sorted(robot_nodes), len(shared)))

    def test_robot_nodes_are_where_the_launch_file_put_them(self):
        expected = rospy.get_param('~robot_nodes', '').split()
        nodes = rosnode.get_node_names()
        self.assertEqual([n for n in expected if n not in nodes], [], nodes)

    def test_probe_service_answers_rosservice_call(self):
        server = self.servers[-1]
        service = rospy.resolve_name(names.probe_service(server))
        rospy.wait_for_service(service, 20.0)
        out = subprocess.run(
            ['rosservice', 'call', service, '{robot_id: 42, seq: 7, stamp: {secs: 3, nsecs: 4}}'],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
            timeout=30)
        self.assertEqual(out.returncode, 0, out.stdout)
        self.assertRegex(out.stdout, r'server_id: %d\b' % server)
        self.assertRegex(out.stdout, r'seq: 7\b')
        self.assertTrue(re.search(r'stamp:\s*\n\s*secs: 3\s*\n\s*nsecs:\s*4\b', out.stdout),
                        out.stdout)

    @classmethod
    def on_log(cls, msg):
        with cls.log_lock:
            cls.logs.append(msg)

    @staticmethod
    def flagged_at(flags, robot, stamp, delivery=rospy.Duration(1.0)):
        """The servers the manager's flags had selected for ``robot`` at ``stamp`` (one
        host: one clock): the last flag stamped more than ``delivery`` before, and any flag
        stamped after that, which may or may not have reached the robot yet (make test runs
        the rostests at low priority beside other tests: 50 ms was once too short, and
        0.5 s once too)."""
        mine = sorted((f.msg for f in flags if f.msg.robot_id == robot),
                      key=lambda f: f.header.stamp)
        settled = [f for f in mine if f.header.stamp <= stamp - delivery]
        racing = [f for f in mine if stamp - delivery < f.header.stamp <= stamp]
        return set(f.server_id for f in settled[-1:] + racing)

    @staticmethod
    def flagged_around(flags, robot, stamp, delivery=rospy.Duration(2.0)):
        """A robot that chooses per task: the servers flags named for ``robot`` from the
        last flag before ``stamp`` to ``delivery`` after it (its choice reaches the manager
        with its next probe sample, or its ranking's period, 1 s; then the manager's flag)."""
        mine = sorted((f.msg for f in flags if f.msg.robot_id == robot),
                      key=lambda f: f.header.stamp)
        before = [f for f in mine if f.header.stamp <= stamp]
        after = [f for f in mine if stamp < f.header.stamp <= stamp + delivery]
        return set(f.server_id for f in before[-1:] + after)

    def doubted(self, robot, stamp, within=rospy.Duration(6.0)):
        """The servers ``robot`` logged, in the ``within`` before ``stamp``, that it ejected
        or that had not answered yet: its own evidence, which goes before the flags (an
        ejection lasts 1 s and then needs good probes; a server not up yet, good probes)."""
        pattern = re.compile(r'robot %d: server (\d+) (ejected|has not answered yet)' % robot)
        with self.log_lock:
            lines = [m.msg for m in self.logs if stamp - within <= m.header.stamp <= stamp]
        return set(int(m.group(1)) for m in map(pattern.match, lines) if m)

    def test_tasks_complete_exactly_once_from_the_flagged_server(self):
        def all_reported():
            return all(len(self.rec.reports_of(r)) >= self.tasks for r in self.robots)
        self.assertTrue(self.rec.wait_for(all_reported, self.timeout),
                        'reports per robot: %s' % dict(
                            (r, len(self.rec.reports_of(r))) for r in self.robots))
        rospy.sleep(1.0)  # let any late duplicate result arrive before counting
        tasks = self.rec.snapshot(self.rec.tasks)
        results = self.rec.snapshot(self.rec.results)
        flags = self.rec.snapshot(self.rec.flags)
        for robot in self.robots:
            reports = self.rec.reports_of(robot)
            self.assertEqual(sorted(r.task_id for r in reports), list(range(1, self.tasks + 1)))
            # a task may fail only for want of a server the robot's own evidence allows
            # (every one ejected or not answering: make test runs this at low priority
            # beside other tests, where a 0.5 s probe or a 1 s first attempt can time out)
            unserved = [r.task_id for r in reports if not r.ok and r.error == NO_SERVER and
                        set(self.servers) <= self.doubted(robot, r.header.stamp)]
            failed = [(r.task_id, r.error) for r in reports
                      if not r.ok and r.task_id not in unserved]
            self.assertEqual(failed, [])
            print('robot %d: tasks %s failed with every server ejected or not answering '
                  '(its log)' % (robot, unserved))
            self.assertLessEqual(len(unserved), MAX_UNSERVED, unserved)
            by_id = dict((r.task_id, r) for r in reports)
            sends = collections.defaultdict(list)     # task id: its sends, in arrival order
            for t in tasks:
                if t.msg.robot_id == robot:
                    sends[t.msg.task_id].append(t.msg)
            self.assertEqual(sorted(sends), [i for i in range(1, self.tasks + 1)
                                             if i not in unserved])
            answers = collections.Counter(
                (r.msg.task_id, r.msg.server_id) for r in results if r.msg.robot_id == robot)
            # direct routing: a server makes its result topic to a robot when the robot
            # first probes it and waits for the robot to connect, not for this test: its
            # answers may pass before the test's own connection to that topic forms
            # (seen at nice 19: tasks 1 and 2). Once the test has heard one answer of a
            # server, every later one must arrive; a server that answered two or more
            # tasks must have been heard
            first_heard, answered = {}, collections.Counter()
            for task_id in sorted(sends):
                server = by_id[task_id].answered_by
                answered[server] += 1
                if answers[(task_id, server)]:
                    first_heard.setdefault(server, task_id)
            self.assertEqual([s for s, n in answered.items() if n >= 2 and s > 0
                              and s not in first_heard], [], answered)
            extra = 0
            for task_id, copies in sends.items():
                report = by_id[task_id]
                targets = [c.server_id for c in copies]
                what = 'task %d of robot %d: sent to %s, answers %s, report %s' % (
                    task_id, robot, targets, sorted(
                        (s, n) for (t, s), n in answers.items() if t == task_id), report)
                # one send per attempt the robot reports, each to another server; the
                # first to the server the report names (later ones: hedged copies)
                self.assertEqual(len(targets), report.attempts, what)
                self.assertEqual(len(set(targets)), len(targets), what)
                self.assertIn(report.server_id, targets, what)
                extra += len(targets) - 1
                # each server that got the task answered it once; no other server did
                for server in targets:
                    self.assertLessEqual(answers[(task_id, server)], 1, what)
                heard = (0, 1) if self.direct and task_id < first_heard.get(
                    report.answered_by, task_id + 1) else (1,)
                self.assertIn(answers[(task_id, report.answered_by)], heard, what)
                self.assertEqual(sum(n for (t, s), n in answers.items()
                                     if t == task_id and s not in targets), 0, what)
                if report.attempts == 1:
                    self.assertEqual(report.answered_by, report.server_id, what)
                if self.mode == 'fixed':
                    self.assertEqual(targets, [self.fixed_server], what)
                elif self.chooses:       # the flags say where the robot's tasks went
                    self.assertIn(report.server_id, self.flagged_around(
                        flags, robot, copies[0].header.stamp), what)
                else:
                    flagged = self.flagged_at(flags, robot, copies[0].header.stamp)
                    if report.server_id not in flagged:   # only if its own evidence said
                        self.assertLessEqual(flagged, self.doubted(    # so just before
                            robot, copies[0].header.stamp), what)
            rtts = sorted(r.rtt for r in reports if r.ok)
            print('robot %d: %d tasks, %d sends beyond the first (hedged or re-sent), round '
                  'trip median %.1f ms, max %.1f ms'
                  % (robot, len(sends), extra, rtts[len(rtts) // 2] * 1e3, rtts[-1] * 1e3))
            # a sort task on one host takes milliseconds: a median near a timeout means
            # tasks waited for attempts that failed
            self.assertTrue(all(r.rtt > 0.0 for r in reports if r.ok), reports)
            self.assertLess(rtts[len(rtts) // 2], 0.25, rtts)
        if self.mode == 'fixed':
            self.assertEqual(set(r.msg.server_id for r in results), {self.fixed_server})
        if self.direct:     # nothing went on the broadcast topics
            self.assertEqual(self.rec.snapshot(self.rec.broadcast), [])


if __name__ == '__main__':
    rostest.rosrun('server_select', 'test_fleet', FleetTest, sys.argv)
