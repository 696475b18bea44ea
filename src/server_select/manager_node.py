"""Manager: ranks each robot's servers by mean probe latency and publishes the choice."""

import threading

import rospy

from server_select import names
from server_select.msg import LatencySample, SelectionFlag
from server_select.node_util import get_param, run
from server_select.params import parse_id_list, parse_non_negative, parse_positive
from server_select.ranking import choose, rank_servers
from server_select.window import LatencyWindow


class ManagerNode(object):
    """The selection manager of paper 1.

    Keeps the samples of the last ``~window`` seconds of every (robot, server) pair, ranks
    each robot's servers by mean round trip (stable sort, ties to the lower id, servers
    without a successful sample excluded) and publishes one ``server_select_flag`` per
    robot every ``1/~publish_rate`` s, and at once when a robot's selected server or the set
    of servers it ranks changes. Rankings are re-evaluated on every sample and every
    ``1/~update_rate`` s, so a server drops out as soon as its last good sample leaves the
    window. Window times are the manager's receive times: robot and manager clocks are
    not shared.

    :ROS Parameters:
        - ``~robots`` (list of int, required), ``~servers`` (list of int, required)
        - ``~window`` (s, 5.0): sample window.
        - ``~publish_rate`` (Hz, 1.0): periodic flag rate.
        - ``~update_rate`` (Hz, 10.0): rate of re-evaluation between samples.
        - ``~hysteresis`` (s, 0.0): keep the current server while its mean is within this
          of the best one (0: always the best, as in the paper).
    :ROS Subscribers:
        - ``latency_R<r>S<s>`` (server_select/LatencySample) for every robot r and server s.
    :ROS Publishers:
        - ``server_select_flag`` (server_select/SelectionFlag)
    """

    def __init__(self):
        self.robots = parse_id_list('~robots', get_param('~robots'))
        self.servers = parse_id_list('~servers', get_param('~servers'))
        self.window = LatencyWindow(parse_positive('~window', get_param('~window', 5.0)))
        publish_rate = parse_positive('~publish_rate', get_param('~publish_rate', 1.0))
        update_rate = parse_positive('~update_rate', get_param('~update_rate', 10.0))
        self.hysteresis = parse_non_negative('~hysteresis', get_param('~hysteresis', 0.0))

        self._lock = threading.Lock()
        self._published = {}  # robot -> (selected server, set of ranked servers)
        self.flag_pub = rospy.Publisher(names.SELECTION_TOPIC, SelectionFlag,
                                        queue_size=4 * len(self.robots))
        self.sample_subs = [
            rospy.Subscriber(names.sample_topic(r, s), LatencySample, self.on_sample,
                             callback_args=(r, s), queue_size=100, tcp_nodelay=True)
            for r in self.robots for s in self.servers]
        self.publish_timer = rospy.Timer(rospy.Duration(1.0 / publish_rate), self.on_publish_timer)
        self.update_timer = rospy.Timer(rospy.Duration(1.0 / update_rate), self.on_update_timer)
        rospy.loginfo('manager: robots %s, servers %s, window %.3g s',
                      self.robots, self.servers, self.window.window)

    def on_sample(self, sample, pair):
        if (sample.robot_id, sample.server_id) != pair:
            rospy.logwarn_throttle(
                10.0, 'manager: ignoring sample for unknown pair robot %d / server %d on the '
                'topic of robot %d / server %d' % ((sample.robot_id, sample.server_id) + pair))
            return
        self.window.add(pair[0], pair[1], rospy.get_time(), sample.ok, sample.rtt)
        self.update(pair[0], only_on_change=True)

    def on_publish_timer(self, _event):
        for robot in self.robots:
            self.update(robot, only_on_change=False)

    def on_update_timer(self, _event):
        for robot in self.robots:
            self.update(robot, only_on_change=True)

    def update(self, robot, only_on_change):
        """Rank ``robot``'s servers now; publish unless unchanged and ``only_on_change``."""
        ranking = rank_servers(self.window.robot_stats(robot, self.servers, rospy.get_time()))
        with self._lock:
            previous, previous_ranked = self._published.get(robot, (None, None))
            selected = choose(ranking, previous, self.hysteresis)
            ranked = frozenset(ranking.ranking)
            changed = previous != selected or previous_ranked != ranked
            if only_on_change and not changed:
                return
            if previous != selected:
                rospy.loginfo('manager: robot %d -> server %s (ranking %s, mean ms %s)', robot,
                              selected, ranking.ranking,
                              ['%.2f' % (m * 1e3) for m in ranking.means])
            self._published[robot] = (selected, ranked)
            flag = SelectionFlag(robot_id=robot, server_id=selected,
                                 ranking=ranking.ranking, mean_latency=ranking.means,
                                 sample_count=ranking.counts, excluded=ranking.excluded)
            flag.header.stamp = rospy.Time.now()
            self.flag_pub.publish(flag)


def main():
    run('manager', ManagerNode)
