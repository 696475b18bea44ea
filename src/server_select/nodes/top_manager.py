"""Top manager of a grouped deployment: assigns each robot to a group of servers."""

import threading
import time

import rospy

from server_select.core.config import names
from server_select.core.fleet.groups import GroupAssigner
from server_select.core.ranking.window import valid_rtt
from server_select.msg import GroupAssignments, LatencySamples, ServerGroup
from server_select.ros.graph import publisher_of
from server_select.ros.node import fleet, param
from server_select.ros.runner import run
from server_select.ros import seal
from server_select.ros.seal import SealedPublisher
from server_select.ros.senders import robot_senders

RESEAL = 5.0      # s between two copies of the unchanged table, with a fleet key


class TopManagerNode(object):
    """The top level of the paper's server groups (§4, future work).

    Robots probe their group's servers and every group's representative (its first
    server) and send one ``latency_samples`` batch per round. This node keeps each robot's
    windowed mean round trip to every representative and assigns the robot to the group
    whose representative is nearest (moving it only when another is nearer by
    ``~group_margin`` s); the assignment table goes out latched on ``group_assignments``
    whenever it changed (at most every 0.2 s). Each group's own manager
    (``manager.launch group:=<g>``, node ``manager_g<g>``) ranks its servers for its robots.

    :ROS Parameters:
        - ``~groups`` (required): ``{group id: [server ids]}``
        - ``~window`` (s, 5.0), ``~group_margin`` (s, 0.001)
        - ``~robot_node`` (``first``): whose samples count for robot {id} (as the manager's)
        - ``~fleet_ns`` (``/``)
    :ROS Subscribers:
        - ``latency_samples`` (server_select/LatencySamples)
    :ROS Publishers:
        - ``group_assignments`` (server_select/GroupAssignments, latched)
    """
    SEAL_ROLE = 'manager'  # what it signs as with a fleet key (core/trust/seal.py)

    def __init__(self):
        self.groups = param('groups')
        self.assigner = GroupAssigner(self.groups, param('window'), param('group_margin'))
        self.senders = robot_senders('top manager', param('robot_node'))
        self._dirty = threading.Event()
        self._published = time.monotonic()
        self.pub = self.sub = self.timer = None

    def start(self):
        self.pub = SealedPublisher(fleet(names.GROUPS_TOPIC), GroupAssignments, queue_size=1,
                                   latch=True)
        self.sub = rospy.Subscriber(fleet(names.SAMPLES_TOPIC), LatencySamples, self.on_batch,
                                    queue_size=1000, tcp_nodelay=True)
        self.timer = rospy.Timer(rospy.Duration(0.2), self.on_timer)
        self.publish()
        rospy.loginfo('top manager: groups %s', self.groups)

    def on_batch(self, batch):
        robot = batch.robot_id
        if not self.senders.admits(batch, lambda: 'samples of robot %d' % robot, robot):
            return
        now = rospy.get_time()
        for server, ok, rtt in zip(batch.server_id, batch.ok, batch.rtt):
            if ok and not valid_rtt(rtt):
                rospy.logwarn_throttle(5.0, 'top manager: ignored a round trip %r of robot %d '
                                       'from %s' % (rtt, robot, publisher_of(batch)))
                continue
            self.assigner.add(robot, server, now, ok, rtt)
        if self.assigner.assign(robot, now):
            self._dirty.set()

    def on_timer(self, _event):
        # with a fleet key, the table again every RESEAL s: a latched copy older than
        # ~fleet_key_max_age would be refused by a robot that connects late
        if self._dirty.is_set() or (seal.enabled() and
                                    time.monotonic() - self._published > RESEAL):
            self._dirty.clear()
            self.publish()

    def publish(self):
        table = self.assigner.table()
        msg = GroupAssignments(
            groups=[ServerGroup(group_id=g, servers=s) for g, s in self.groups.items()],
            robot_id=[r for r, _ in table], group_id=[g for _, g in table])
        msg.header.stamp = rospy.Time.now()
        self.pub.publish(msg)
        self._published = time.monotonic()


def main():
    run('top_manager', TopManagerNode)
