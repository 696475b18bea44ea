"""Watches a cooperative search: who found which target when; ends when all are found."""

import json
import threading

import rospy

from server_select.core.config import names
from server_select.core.config.params import ParamError
from server_select.core.util.tables import markdown_table
from server_select.msg import FoundTarget
from server_select.ros.node import fleet, param
from server_select.ros.runner import run
from server_select.ros.senders import SenderGate
from server_select.vision.search import SearchError, SearchWorld


class SearchMonitorNode(object):
    """Ground truth referee of the search demo (it knows where the targets are).

    Matches each ``found_targets`` record to the nearest placed target within
    ``~radius``; prints who found what and when once every target is found (or at
    ``~timeout``), then shuts down (``required`` in the launch file ends the run).

    :ROS Parameters:
        - ``~area`` (str, required): the search area YAML the robots use.
        - ``~radius`` (area pixels, 150.0), ``~timeout`` (s, 180.0)
        - ``~output`` (str, ''): also write the outcome as JSON here.
    :ROS Subscribers:
        - ``found_targets`` (server_select/FoundTarget)
    """

    def __init__(self):
        try:
            self.world = SearchWorld.load(param('area'))
        except SearchError as error:
            raise ParamError('~area: %s' % error)
        self.radius = param('radius')
        timeout = param('timeout')
        self.output = param('output')
        self._lock = threading.Lock()
        self.found = {}
        self.reports = []
        self._heard = set()       # (robot, task, label, x, y) of each report heard
        self.false_alarms = []
        self.began = rospy.get_time()
        self.gate = SenderGate('search monitor', 'a node of the fleet')   # key: sealed only
        self.sub = rospy.Subscriber(fleet(names.FOUND_TARGETS_TOPIC), FoundTarget, self.on_found,
                                    queue_size=100)
        self.timer = rospy.Timer(rospy.Duration(timeout), self.finish, oneshot=True)
        rospy.loginfo('search monitor: %d targets to find', len(self.world.targets))

    def on_found(self, msg):
        if not self.gate.admits(msg, 'a found target'):
            return
        name = self.world.target_at(msg.x, msg.y, self.radius)
        t = rospy.get_time() - self.began
        report = (msg.robot_id, msg.task_id, msg.label, msg.x, msg.y)
        with self._lock:
            if report in self._heard:
                return      # a find sent again on a new connection: one report still
            self._heard.add(report)
            self.reports.append((t, msg.robot_id, name, msg.x, msg.y))
            if name is None:
                self.false_alarms.append((t, msg.robot_id, msg.x, msg.y))
                rospy.logwarn('search monitor: robot %d reported %s at (%.0f, %.0f): no target '
                              'there', msg.robot_id, msg.label, msg.x, msg.y)
                return
            if name in self.found:
                rospy.logwarn('search monitor: %s reported again by robot %d (first by robot %d)',
                              name, msg.robot_id, self.found[name][1])
                return
            self.found[name] = (t, msg.robot_id)
            done = len(self.found) == len(self.world.targets)
        rospy.loginfo('search monitor: robot %d found %s at %.1f s', msg.robot_id, name, t)
        if done:
            self.finish()

    def finish(self, _event=None):
        with self._lock:
            rows = []
            for target in self.world.targets:
                t, robot = self.found.get(target.name, (None, None))
                rows.append((target.name, 'robot %d' % robot if robot is not None else 'not found',
                             '%.1f' % t if t is not None else '-'))
            duplicates = len(self.reports) - len(self.found) - len(self.false_alarms)
            outcome = ('%d of %d targets found; %d duplicate reports, %d false alarms'
                       % (len(self.found), len(self.world.targets), duplicates,
                          len(self.false_alarms)))
            result = {'found': dict((k, {'robot': v[1], 't': v[0]}) for k, v in self.found.items()),
                      'targets': len(self.world.targets), 'duplicates': duplicates,
                      'false_alarms': len(self.false_alarms)}
        print('\ncooperative search\n\n' + markdown_table(('target', 'found by', 'at s'), rows)
              + '\n\n' + outcome + '\n', flush=True)
        if self.output:
            with open(self.output, 'w') as stream:
                json.dump(result, stream, indent=1)
        rospy.signal_shutdown('search finished')


def main():
    run('search_monitor', SearchMonitorNode)
