"""Which node is which robot, at a server with a fleet key: the probes say.

ROS 1 lets any node publish a task under any robot id, claim any callerid in its
connection header, and name rates in a probe. With a fleet key a robot seals a probe
request (robot role) when what it announces changes, and once a second; a sealed probe
binds its robot id to the node that sent it and to that node's XML-RPC URI, which the
probe names, for :data:`ROBOT_LEASE` s, renewed by each (another node's claim meanwhile is
refused; a robot restarted under another name is bound again once the old lease ends).
Only a bound robot's sealed probes announce rates and prepare its result topics, and only
tasks that come over a connection this server made to that URI are taken (the URI is
where this node connected, from the master's list of publishers: a publisher claiming
``callerid=/robot1`` from elsewhere is not robot 1; a robot restarted under its name is
taken at its new URI once the master lists it there, before its next sealed probe comes).
The others are dropped unanswered (an
answer to a made-up robot costs a publisher), counted by sender, in a line at most every
5 s that also says how many tasks were taken meanwhile. Without a key everything counts.
"""

import threading

import rosgraph
import rospy
from rospy.impl import tcpros_base

from server_select.core.fleet.leases import Leases
from server_select.core.trust.senders import Throttle
from server_select.core.util.bounded import PEER_CHARS, PeerCounter, peer
from server_select.ros import seal
from server_select.ros.graph import publisher_of
from server_select.ros.senders import warn

ROBOT_LEASE = 10.0       # s a signed probe binds its robot id (robots probe every ~0.5 s)
# the connection header key under which this node notes where it connected (any value a
# publisher sent under it is replaced)
PUBLISHER_URI = 'server_select_connected_to'
_VALIDATE = []


def note_where_connected():
    """From now on, every connection this node makes to a publisher notes in its header
    (``msg._connection_header``) the URI it connected to (idempotent)."""
    if _VALIDATE:
        return
    _VALIDATE.append(tcpros_base.TCPROSTransport._validate_header)

    def validate(transport, header):
        header[PUBLISHER_URI] = transport.endpoint_id    # (set before the socket's connect)
        _VALIDATE[0](transport, header)
    tcpros_base.TCPROSTransport._validate_header = validate


def binding(node, uri):
    """A node at its XML-RPC URI, as the log names it (each cut to a peer name's length: a
    longer URI binds nothing any connection matches)."""
    return '%s at %s' % (peer(node), peer(uri or '?', 2 * PEER_CHARS))


class RobotAdmission(object):
    """A server's binding of robot ids to nodes (:meth:`probe`) and the gate of its tasks
    (:meth:`admits`); ``who`` names it in the log. Thread-safe."""

    def __init__(self, who, service, clock=None):
        self.who, self.service = who, service
        self.keyed = seal.enabled()
        self._clock = clock or rospy.get_time
        self.leases = Leases()        # robot id -> its node (by name)
        self._uris = {}               # robot id -> its node's URI, as its last sealed probe said
        self._asked = {}              # node -> (when, the URI the master listed it at)
        self._lock = threading.Lock()
        self._expired_at = 0.0
        self.taken = 0
        self.refused = PeerCounter()      # sender -> tasks dropped (the latest senders)
        self._probe_throttle, self._task_throttle = Throttle(5.0), Throttle(5.0)
        if self.keyed:
            note_where_connected()

    def probe(self, request):
        """Whether ``request`` is its robot's own (then it binds the robot id to its node):
        True without a key; an observer's (robot 0) binds nothing."""
        if not self.keyed:
            return True
        if request.robot_id == 0:
            return False
        sender = (getattr(request, '_connection_header', None) or {}).get('callerid', '?')
        if not request.seal.mac and self.leases.holder(request.robot_id, self._clock()) == sender:
            return False          # its robot's, between the ones it seals (once a second)
        why = seal.request_refusal(request, self.service)
        if why is None:
            now = self._clock()
            self._expire(now)
            _changed, holder = self.leases.renew(request.robot_id, sender, now, ROBOT_LEASE)
            if holder is None:      # (a robot restarted under its name: at its new URI)
                with self._lock:
                    self._uris[request.robot_id] = binding(sender, request.node_uri)
                return True
            why = 'robot %d is %s\'s until its probes stop for %g s' % (
                request.robot_id, holder, ROBOT_LEASE)
        warn(self._probe_throttle, '%s: a probe of robot %d from %s announces nothing and '
             'prepares nothing (%s, by the fleet key)'
             % (self.who, request.robot_id, peer(sender), peer(why, 4 * PEER_CHARS)))
        return False

    def _restarted_at(self, node, uri):
        """Whether the master lists ``node`` (the bound robot's name) at ``uri`` now: the
        robot restarted there, and a task came before its first sealed probe did. A
        publisher elsewhere claiming the name is not listed there. Asked once a second per
        node at most."""
        now = self._clock()
        with self._lock:
            asked = self._asked.get(node)
            if asked is not None and now - asked[0] < 1.0:
                return asked[1] == uri
        try:
            listed = rosgraph.Master(rospy.get_name()).lookupNode(node)
        except (rosgraph.MasterError, OSError):
            listed = None
        with self._lock:
            if len(self._asked) >= 64 and node not in self._asked:
                self._asked.clear()
            self._asked[node] = (now, listed)
        return listed is not None and listed == uri

    def _expire(self, now):
        with self._lock:
            if now - self._expired_at < 1.0:
                return
            self._expired_at = now
        for robot in self.leases.expire(now):
            with self._lock:
                if self.leases.holder(robot) is None:     # (not bound again meanwhile)
                    self._uris.pop(robot, None)

    def admits(self, task):
        """Whether ``task`` comes from the node its robot id is bound to (always without a
        key)."""
        if not self.keyed:
            return True
        name = publisher_of(task)
        uri = (getattr(task, '_connection_header', None) or {}).get(PUBLISHER_URI)
        sender = binding(name, uri)
        holder = self.leases.holder(task.robot_id, self._clock())      # ends in time
        with self._lock:
            bound = self._uris.get(task.robot_id) if holder is not None else None
        if bound is not None and sender != bound and name == holder and \
                self._restarted_at(name, uri):
            with self._lock:        # its sealed probe there may not have come yet
                self._uris[task.robot_id] = bound = sender
        with self._lock:
            if bound is not None and sender == bound:
                self.taken += 1
                return True
            refused, taken = self.refused.add(sender), self.taken
        sender = peer(sender)
        warn(self._task_throttle, '%s: dropped a task of robot %d from %s (%s): %d of its '
             'tasks dropped, %d robots\' tasks taken so far'
             % (self.who, task.robot_id, sender, 'no signed probe of robot %d' % task.robot_id
                if bound is None else 'robot %d is %s' % (task.robot_id, bound), refused,
                taken))
        return False
