"""Manager: ranks each robot's servers by mean probe latency and publishes the choice."""

import rospy

from server_select.core import names
from server_select.core.params import ParamError
from server_select.core.ranking import choose, rank_servers
from server_select.core.window import LatencyWindow, valid_rtt
from server_select.msg import LatencySample
from server_select.ros.flags import FlagPublisher
from server_select.ros.graph import publisher_of
from server_select.ros.node import fleet, owned_by, param, run


class ManagerNode(object):
    """The selection manager of paper 1.

    Keeps the samples of the last ``~window`` seconds of every (robot, server) pair, ranks
    each robot's servers by mean round trip (stable sort, ties to the lower id, servers
    without a successful sample excluded) and publishes one ``server_select_flag`` per
    robot every ``1/~publish_rate`` s, and at once when a robot's selected server or the set
    of servers it ranks changes. Rankings are re-evaluated on every sample and every
    ``1/~update_rate`` s, so a server drops out as soon as its last good sample leaves the
    window. Window times are the manager's receive times: robot and manager clocks are
    not shared. A robot gets no flag before its first sample (a restarted manager does not
    publish an empty ranking over a robot's working choice). Samples claiming another
    pair, with an impossible round trip, or not published by ``~robot_node`` are ignored
    with a throttled warning naming the publisher.

    :ROS Parameters:
        - ``~robots`` (list of int, required), ``~servers`` (list of int, required)
        - ``~window`` (s, 5.0): sample window.
        - ``~publish_rate`` (Hz, 1.0): periodic flag rate.
        - ``~update_rate`` (Hz, 10.0): rate of re-evaluation between samples.
        - ``~hysteresis`` (s, 0.0): keep the current server while its mean is within this
          of the best one (0: always the best, as in the paper).
        - ``~robot_node`` (``/robot{id}``): the node, or the namespace of the nodes, whose
          samples count for robot {id} (``*``: any publisher).
        - ``~fleet_ns`` (``/``): namespace of the fleet-level topics and services.
    :ROS Subscribers:
        - ``latency_R<r>S<s>`` (server_select/LatencySample) for every robot r and server s.
    :ROS Publishers:
        - ``server_select_flag`` (server_select/SelectionFlag)
    """

    def __init__(self):
        self.robots = param('robots')
        self.servers = param('servers')
        self.window = LatencyWindow(param('window'))
        self.publish_rate = param('publish_rate')
        self.update_rate = param('update_rate')
        self.hysteresis = param('hysteresis')
        pattern = param('robot_node')
        try:
            self.robot_node = dict(   # None: any publisher
                (r, rospy.resolve_name(pattern.format(id=r)) if pattern else None)
                for r in self.robots)
        except (KeyError, IndexError, ValueError) as error:
            raise ParamError('~robot_node: %r is not a node name with {id}: %s'
                             % (pattern, error))
        self.heard = set()
        self.flags = FlagPublisher(self.robots, 'manager')
        self.sample_subs = []
        self.timers = []

    def start(self):
        self.sample_subs = [
            rospy.Subscriber(fleet(names.sample_topic(r, s)), LatencySample, self.on_sample,
                             callback_args=(r, s), queue_size=100, tcp_nodelay=True)
            for r in self.robots for s in self.servers]
        self.timers = [
            rospy.Timer(rospy.Duration(1.0 / self.publish_rate), lambda _e: self.update_all(False)),
            rospy.Timer(rospy.Duration(1.0 / self.update_rate), lambda _e: self.update_all(True))]
        rospy.loginfo('manager: robots %s, servers %s, window %.3g s',
                      self.robots, self.servers, self.window.window)

    def on_sample(self, sample, pair):
        why = self.refuse(sample, pair)
        if why:
            rospy.logwarn_throttle(5.0, 'manager: ignored a sample on %s published by %s: %s'
                                   % (names.sample_topic(*pair), publisher_of(sample), why))
            return
        self.window.add(pair[0], pair[1], rospy.get_time(), sample.ok, sample.rtt)
        self.heard.add(pair[0])
        self.update(pair[0], only_on_change=True)

    def refuse(self, sample, pair):
        """Why ``sample``, received on the topic of ``pair``, must be ignored (or None)."""
        if (sample.robot_id, sample.server_id) != pair:
            return 'it claims robot %d / server %d' % (sample.robot_id, sample.server_id)
        if sample.ok and not valid_rtt(sample.rtt):
            return 'round trip %r is not a finite number >= 0' % sample.rtt
        expected = self.robot_node.get(pair[0])
        if expected is not None and not owned_by(publisher_of(sample), expected):
            return 'robot %d is %s (or a node in its namespace)' % (pair[0], expected)
        return None

    def update_all(self, only_on_change):
        for robot in self.robots:
            if robot in self.heard:   # silent for a robot until it has sent samples
                self.update(robot, only_on_change)

    def update(self, robot, only_on_change):
        """Rank ``robot``'s servers now; publish unless unchanged and ``only_on_change``."""
        ranking = rank_servers(self.window.robot_stats(robot, self.servers, rospy.get_time()))
        self.flags.offer(robot, ranking, only_on_change,
                         lambda previous: choose(ranking, previous, self.hysteresis))


def main():
    run('manager', ManagerNode)
