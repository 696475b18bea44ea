"""Servers that come and go at run time (fleet profile).

Every server announces itself, latched, on ``server_announcements`` every
``~announce_period`` s with a lease of a few periods (:mod:`server_select.core.fleet.leases`),
and says when it leaves. The manager keeps the leases and publishes the members' ids,
latched, on ``fleet_servers`` when they change; robots with ``~discover`` probe what it
lists on top of their static ``~servers``. Nobody asks the master: a server that shuts
down leaves the list at once, one that dies or hangs when its lease ends (its robots'
health ejects it before that).
"""

import threading
import warnings

import rospy

from server_select.core.config import names
from server_select.core.fleet.groups import probe_set
from server_select.core.fleet.leases import LEASE_PERIODS, Leases
from server_select.msg import FleetServers, GroupAssignments, ServerAnnouncement
from server_select.ros.graph import publisher_of
from server_select.ros.senders import SenderGate
from server_select.ros.node import fleet
from server_select.ros import seal
from server_select.ros.seal import SealedPublisher


class ServerAnnouncer(object):
    """Server side: "server ``server_id`` is in the fleet" every ``period`` s, and "it
    leaves" at :meth:`leave`."""

    def __init__(self, server_id, period):
        self.server_id, self.period = server_id, period
        self.pub = self.timer = None
        self.probe_uri = ''      # its probe service's address, once it serves it

    def start(self):
        with warnings.catch_warnings():     # synchronous on purpose: the leaving
            warnings.simplefilter('ignore')  # announcement is written before the node ends
            self.pub = SealedPublisher(fleet(names.ANNOUNCE_TOPIC), ServerAnnouncement,
                                       latch=True)
        self.announce()
        self.timer = rospy.Timer(rospy.Duration(self.period), self.announce)

    def announce(self, _event=None, lease=None):
        msg = ServerAnnouncement(server_id=self.server_id, lease=LEASE_PERIODS * self.period
                                 if lease is None else lease, probe_uri=self.probe_uri)
        msg.header.stamp = rospy.Time.now()
        self.pub.publish(msg)

    def leave(self):
        if self.timer is not None:
            self.timer.shutdown()
            self.announce(lease=0.0)


class ServerRegistry(object):
    """Manager side: the servers whose announcements hold a lease, published on
    ``fleet_servers`` when they change (and, with a fleet key, again every second: a
    latched copy older than ``~fleet_key_max_age`` would be refused by a robot that
    connects late). The first list goes out ``grace`` s after the start, when every
    running server has been heard (a restarted manager must not tell the robots that
    the fleet is empty)."""

    def __init__(self, grace, on_leave=None, clock=None):
        self.leases = Leases()
        self.on_leave = on_leave      # on_leave(servers): they left the list
        self._clock = clock or rospy.get_time
        self.grace, self._since = grace, None
        self.senders = SenderGate('manager', 'a server')
        self._lock = threading.Lock()
        self.servers = None
        self.pub = self.sub = self.timer = None

    def start(self):
        self.pub = SealedPublisher(fleet(names.SERVERS_TOPIC), FleetServers, queue_size=1,
                                   latch=True)
        self._since = self._clock()
        self.sub = rospy.Subscriber(fleet(names.ANNOUNCE_TOPIC), ServerAnnouncement,
                                    self.on_announcement, queue_size=1000)
        self.timer = rospy.Timer(rospy.Duration(1.0), self.on_check)

    def on_announcement(self, msg):
        if not self.senders.admits(msg, 'a server announcement'):
            return
        node = publisher_of(msg)
        try:
            changed, other = self.leases.renew(msg.server_id, node, self._clock(), msg.lease)
        except ValueError as error:
            rospy.logwarn_throttle(5.0, 'manager: ignored an announcement of server %d by %s: '
                                   '%s' % (msg.server_id, node, error))
            return
        if other is not None:
            rospy.logwarn_throttle(5.0, 'manager: ignored an announcement of server %d by %s: '
                                   'the id is %s\'s until it leaves or its lease ends'
                                   % (msg.server_id, node, other))
        if changed:
            self.publish()

    def on_check(self, _event):
        self.leases.expire(self._clock())
        self.publish(again=seal.enabled())

    def publish(self, again=False):
        with self._lock:
            found = self.leases.members()
            if (found == self.servers and not again) or \
                    self._clock() < self._since + self.grace:
                return
            left = sorted(set(self.servers or ()) - set(found))
            if self.servers is not None and found != self.servers:
                rospy.loginfo('manager: servers in the fleet now %s (joined %s, left %s)',
                              found, sorted(set(found) - set(self.servers)),
                              sorted(set(self.servers) - set(found)))
            self.servers = found
            msg = FleetServers(servers=found)
            msg.header.stamp = rospy.Time.now()
            self.pub.publish(msg)
        if left and self.on_leave is not None:
            self.on_leave(left)

    def shutdown(self):
        if self.timer is not None:
            self.timer.shutdown()


class ServerAnnouncements(object):
    """Robot side: ``on_change(added, removed)`` when the announced list changes. Servers
    in ``static`` are never removed. Only announcements of ``manager_node`` count."""

    def __init__(self, static, on_change, manager_node, robot_id):
        self.static = set(static)
        self.known = set(static)
        self.on_change, self.robot_id = on_change, robot_id
        self.senders = SenderGate('robot %d' % robot_id, 'the manager', manager_node)
        self._lock = threading.Lock()
        self.sub = None

    def start(self):
        self.sub = rospy.Subscriber(fleet(names.SERVERS_TOPIC), FleetServers, self.on_servers,
                                    queue_size=10)

    def on_servers(self, msg):
        if not self.senders.admits(msg, 'a server list'):
            return
        with self._lock:
            wanted = self.static | set(msg.servers)
            added, removed = sorted(wanted - self.known), sorted(self.known - wanted)
            self.known = wanted
        if added or removed:
            rospy.loginfo('robot %d: servers joined %s, left %s', self.robot_id, added, removed)
            self.on_change(added, removed)


class GroupAssignmentsListener(object):
    """Grouped deployments: ``on_assignments(groups, assigned)`` for each table of the top
    manager (``{group: [servers]}``, ``{robot: group}``); tables from other nodes are
    ignored with a throttled warning naming the publisher."""

    def __init__(self, top_node, on_assignments, who):
        self.on_assignments = on_assignments
        self.senders = SenderGate(who, 'the top manager', rospy.resolve_name(top_node))
        self.sub = None

    def start(self):
        self.sub = rospy.Subscriber(fleet(names.GROUPS_TOPIC), GroupAssignments, self.on_msg,
                                    queue_size=10)

    def on_msg(self, msg):
        if not self.senders.admits(msg, 'group assignments'):
            return
        groups = dict((g.group_id, list(g.servers)) for g in msg.groups)
        self.on_assignments(groups, dict(zip(msg.robot_id, msg.group_id)))


class GroupFollower(object):
    """Robot side of a grouped deployment: probe what the top manager's table says (this
    robot's group's servers and every group's representative, plus ``static``), and take
    flags from the group's manager: ``on_change(added, removed)``, ``on_group(group,
    servers)`` when the robot's group or its servers (where its tasks may go) change."""

    def __init__(self, robot_id, static, top_node, on_change, on_group):
        self.robot_id = robot_id
        self.announced = ServerAnnouncements(static, on_change, None, robot_id)
        self.listener = GroupAssignmentsListener(top_node, self.on_assignments,
                                                 'robot %d' % robot_id)
        self.on_group = on_group
        self.group, self.servers = None, None

    def start(self):
        self.listener.start()

    def on_assignments(self, groups, assigned):
        group = assigned.get(self.robot_id)
        self.announced.on_servers(FleetServers(servers=sorted(probe_set(groups, group))))
        if group is None:
            return
        servers = sorted(groups.get(group, []))
        if group != self.group:
            rospy.loginfo('robot %d: in server group %d (servers %s)', self.robot_id, group,
                          servers)
        if (group, servers) != (self.group, self.servers):
            self.group, self.servers = group, servers
            self.on_group(group, servers)
