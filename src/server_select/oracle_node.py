"""Oracle selection: the truly nearest server according to the testbed scenario."""

import threading

import rospy

from server_select import names
from server_select.msg import SelectionFlag
from server_select.node_util import get_param, run
from server_select.params import ParamError, parse_id_list, parse_positive
from server_select.scenario import Scenario, ScenarioError


class OracleNode(object):
    """Stands in for the manager in the ``oracle`` evaluation mode.

    Publishes ``server_select_flag`` like the manager, but ranks each robot's servers by
    the one-way delay the scenario file gives the links at this moment (down links
    excluded), so robots always use the truly nearest server: the bound any measuring
    policy can reach. ``mean_latency`` carries the scenario's round trip (2 x delay).

    :ROS Parameters:
        - ``~scenario`` (str, required): scenario YAML file.
        - ``~t0`` (float, required): scenario time zero, epoch seconds.
        - ``~robots`` (list of int, required)
        - ``~publish_rate`` (Hz, 1.0), ``~update_rate`` (Hz, 20.0)
    :ROS Publishers:
        - ``server_select_flag`` (server_select/SelectionFlag)
    """

    def __init__(self):
        path = get_param('~scenario')
        try:
            self.scenario = Scenario.load(path)
        except ScenarioError as error:
            raise ParamError('~scenario: %s' % error)
        self.t0 = float(get_param('~t0'))
        self.robots = parse_id_list('~robots', get_param('~robots'))
        for robot in self.robots:
            try:
                self.scenario.host_for('robot', robot)
            except KeyError:
                raise ParamError('~robots: robot %d is not in scenario %s' % (robot, path))
        publish_rate = parse_positive('~publish_rate', get_param('~publish_rate', 1.0))
        update_rate = parse_positive('~update_rate', get_param('~update_rate', 20.0))
        self._lock = threading.Lock()
        self._published = {}
        self.flag_pub = rospy.Publisher(names.SELECTION_TOPIC, SelectionFlag,
                                        queue_size=4 * len(self.robots))
        self.publish_timer = rospy.Timer(rospy.Duration(1.0 / publish_rate),
                                         lambda _e: self.update(False))
        self.update_timer = rospy.Timer(rospy.Duration(1.0 / update_rate),
                                        lambda _e: self.update(True))
        rospy.loginfo('oracle: scenario %s, robots %s', self.scenario.name, self.robots)

    def ranking(self, robot, t):
        host = self.scenario.host_for('robot', robot)
        up, down = [], []
        for server in sorted(self.scenario.of_role('server'), key=lambda h: h.id):
            state = self.scenario.link(host.name, server.name, t)
            (down if state.down else up).append((state.delay, server.id))
        ranked = sorted(up, key=lambda pair: pair[0])
        return ranked, [s for _, s in down]

    def update(self, only_on_change):
        t = rospy.get_time() - self.t0
        for robot in self.robots:
            ranked, excluded = self.ranking(robot, t)
            selected = ranked[0][1] if ranked else SelectionFlag.NO_SERVER
            with self._lock:
                if only_on_change and self._published.get(robot) == selected:
                    continue
                self._published[robot] = selected
                flag = SelectionFlag(robot_id=robot, server_id=selected,
                                     ranking=[s for _, s in ranked],
                                     mean_latency=[2e-3 * d for d, _ in ranked],
                                     sample_count=[0] * len(ranked), excluded=excluded)
                flag.header.stamp = rospy.Time.now()
                self.flag_pub.publish(flag)


def main():
    run('oracle', OracleNode)
