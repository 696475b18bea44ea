"""Servers that come and go at run time (fleet profile).

The master already knows every server: each hosts a ``latency_S<s>`` probe service. The
manager looks there every ``~discovery_period`` s (one master call per period for the
whole fleet, rather than one per robot) and publishes the ids, latched, on
``fleet_servers`` when they change; robots with ``~discover`` probe what it lists on top
of their static ``~servers``. A server that shuts down unregisters its service and is
dropped from the list; one that dies without unregistering is dropped by the robots'
health (failed probes) and leaves the manager's rankings when its window is empty.
"""

import threading

import rosgraph
import rospy

from server_select.core import names
from server_select.core.groups import probe_set
from server_select.msg import FleetServers, GroupAssignments
from server_select.ros.senders import SenderGate
from server_select.ros.node import fleet
from server_select.ros import seal
from server_select.ros.seal import SealedPublisher


class ServerDiscovery(object):
    """Manager side: the probe services in the master, published on ``fleet_servers``."""

    def __init__(self, period, system_state=None):
        self.period = period
        self._system_state = system_state or (
            lambda: rosgraph.Master(rospy.get_name()).getSystemState())
        self.servers = None
        self.pub = self.timer = None

    def start(self):
        self.pub = SealedPublisher(fleet(names.SERVERS_TOPIC), FleetServers, queue_size=1,
                                   latch=True)
        self.look()
        self.timer = rospy.Timer(rospy.Duration(self.period), self.look)

    def look(self, _event=None):
        try:
            _, _, services = self._system_state()
        except (rosgraph.MasterError, OSError) as error:
            rospy.logwarn_throttle(30.0, 'manager: cannot list the servers in the master: %s'
                                   % error)
            return
        ns = fleet('')
        found = sorted(s for s in (names.probe_server_id(name, ns) for name, nodes in services
                                   if nodes) if s is not None)
        if found != self.servers:
            if self.servers is not None:
                rospy.loginfo('manager: servers in the fleet now %s (joined %s, left %s)',
                              found, sorted(set(found) - set(self.servers)),
                              sorted(set(self.servers) - set(found)))
            self.servers = found
        elif not seal.enabled():
            return
        # with a fleet key, the list again at every look: a latched copy older than
        # ~fleet_key_max_age would be refused by a robot that connects late
        msg = FleetServers(servers=found)
        msg.header.stamp = rospy.Time.now()
        self.pub.publish(msg)

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
    flags from the group's manager: ``on_change(added, removed)``, ``on_group(group)``."""

    def __init__(self, robot_id, static, top_node, on_change, on_group):
        self.robot_id = robot_id
        self.announced = ServerAnnouncements(static, on_change, None, robot_id)
        self.listener = GroupAssignmentsListener(top_node, self.on_assignments,
                                                 'robot %d' % robot_id)
        self.on_group = on_group
        self.group = None

    def start(self):
        self.listener.start()

    def on_assignments(self, groups, assigned):
        group = assigned.get(self.robot_id)
        self.announced.on_servers(FleetServers(servers=sorted(probe_set(groups, group))))
        if group is not None and group != self.group:
            rospy.loginfo('robot %d: in server group %d (servers %s)', self.robot_id, group,
                          groups.get(group))
            self.group = group
            self.on_group(group)
