"""Oracle selection: the truly nearest server according to the testbed scenario."""

import rospy

from server_select.core.ranking.rank import NO_SERVER, Ranking
from server_select.core.config.params import ParamError
from server_select.ros.flags import FlagPublisher
from server_select.ros.node import param
from server_select.ros.runner import run
from server_select.testbed.scenario import Scenario, ScenarioError


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
        - ``server_select_flag`` (server_select/SelectionFlag); with ``~profile`` fleet
          each robot's ``robot_<r>/server_select_flag`` (``~flag_stream``)
    """
    SEAL_ROLE = 'manager'  # what it signs as with a fleet key (core/trust/seal.py)

    def __init__(self):
        path = param('scenario')
        try:
            self.scenario = Scenario.load(path)
        except ScenarioError as error:
            raise ParamError('~scenario: %s' % error)
        self.t0 = param('t0')
        self.robots = param('robots')
        for robot in self.robots:
            try:
                self.scenario.host_for('robot', robot)
            except KeyError:
                raise ParamError('~robots: robot %d is not in scenario %s' % (robot, path))
        self.publish_rate = param('publish_rate')
        self.update_rate = param('update_rate', default=20.0)
        self.flags = FlagPublisher('oracle', queue_size=4 * len(self.robots))
        self.timers = []

    def start(self):
        self.timers = [
            rospy.Timer(rospy.Duration(1.0 / self.publish_rate), lambda _e: self.update(False)),
            rospy.Timer(rospy.Duration(1.0 / self.update_rate), lambda _e: self.update(True))]
        rospy.loginfo('oracle: scenario %s, robots %s', self.scenario.name, self.robots)

    def update(self, only_on_change):
        t = rospy.get_time() - self.t0
        for robot in self.robots:
            ranked, down = self.scenario.ranking(robot, t)
            servers = [s for _, s in ranked]
            self.flags.offer(robot, Ranking(
                selected=servers[0] if servers else NO_SERVER, ranking=servers,
                means=[2e-3 * d for d, _ in ranked], counts=[0] * len(ranked), excluded=down,
                reason='the nearest by the scenario' if servers else 'every server down'),
                only_on_change)


def main():
    run('oracle', OracleNode)
