"""Which node is which server, and which answers to a robot's probes are its servers' own,
by the fleet key (parts of the :class:`~server_select.ros.prober.Prober`)."""

import threading
import time

import rospy

from server_select.core.config import names
from server_select.core.fleet.leases import Leases
from server_select.core.trust.senders import Throttle
from server_select.msg import ServerAnnouncement
from server_select.ros import seal
from server_select.ros.graph import publisher_of
from server_select.ros.node import fleet
from server_select.ros.senders import SenderGate, warn


SIGN_PERIOD = 1.0     # s between a robot's sealed probes of one server (its lease there: 10)


class ProbeSeal(object):
    """``node_of(server, refresh)`` names the node that is a server (with a key, the one its
    sealed announcement names; else the one the master lists for its probe service);
    ``addresses`` (a :class:`ProbeAddresses`, with a key, or
    None) the address its sealed announcement names, which is probed."""

    def __init__(self, robot_id, node_of=None, addresses=None, clock=time.monotonic):
        self.robot_id, self.addresses = robot_id, addresses
        self.node_of = node_of or (lambda server, refresh=False: None)
        self._forged = Throttle(5.0)
        self._clock = clock
        self._lock = threading.Lock()
        self._signed = {}       # server -> (what the last signed probe said, when)

    def sign(self, server, request):
        """``request`` to ``server``, sealed (with a key) when what it announces changed or
        :data:`SIGN_PERIOD` s after the last one sealed: a server binds the robot, and
        keeps its rates, from its sealed probes only (signing every probe made a keyed
        robot cost 1.51x a keyless one's CPU)."""
        said, now = (tuple(request.task_kinds), tuple(request.task_rates)), self._clock()
        with self._lock:
            last = self._signed.get(server)
            if last is not None and last[0] == said and now - last[1] < SIGN_PERIOD:
                return request
            self._signed[server] = (said, now)
        return seal.seal(request, fleet(names.probe_service(server)))

    def forget(self, server):
        """The next probe of ``server`` is sealed (its last failed: it may be new)."""
        with self._lock:
            self._signed.pop(server, None)

    def proxy_args(self, server):
        """What a server's TimedServiceProxy is given: its pinned address and what to do
        when the master lists another (nothing without announced addresses)."""
        return (self._pinned(server), self._moved(server)) if self.addresses else ()

    def _pinned(self, server):
        return lambda: (self.addresses.of(server) or (None, None))[0]

    def _moved(self, server):
        def moved(master, pinned):
            warn(self._forged, 'robot %d: the master lists %s for the probe service of server '
                 '%d, but the server\'s sealed announcement says %s: probing that (another '
                 'node registered the service)' % (self.robot_id, master, server, pinned))
        return moved

    def node(self, server, refresh=False):
        """The node whose seal a probe answer of ``server`` must carry (``node_of``'s)."""
        return self.node_of(server, refresh)

    def forgery(self, server, response, proxy, request):
        """Why the answer is not the server's, by the fleet key (None: it is, or no key)."""
        if not seal.enabled():   # nothing to check, no node to look up; a sealed answer
            return seal.answer_refusal(    # makes a keyless robot say it lacks the key
                response, proxy.resolved_name, proxy.uri, request, 'server %d' % server)
        node = self.node(server)
        forged = seal.answer_refusal(response, proxy.resolved_name, proxy.uri, request,
                                     node or '?')
        if forged is not None and not forged.endswith('(replayed)'):
            node = self.node(server, True)         # the server may have been restarted
            forged = seal.answer_refusal(response, proxy.resolved_name, proxy.uri, request,
                                         node or '?')
        if forged is not None and 'check NTP' in forged:    # the clocks, not an impostor
            warn(self._forged, 'robot %d: ignored a probe answer of %s from node %s: %s'
                 % (self.robot_id, proxy.resolved_name, node, forged))
        elif forged is not None:
            warn(self._forged, 'robot %d: ignored a probe answer of %s from node %s at %s (%s, '
                 'by the fleet key): not server %d'
                 % (self.robot_id, proxy.resolved_name, node, proxy.uri, forged, server))
        return forged


class ProbeAddresses(object):
    """Robot side, with a fleet key: where each server serves its probe service, and under
    which node name, as its sealed announcements say (ROS 1 lets any node register any
    service at the master, at its own address and under another node's name; a server's
    announcement, sealed with the fleet key, is the witness instead). A server id is the
    first announcing node's until that node leaves or its lease ends (:class:`Leases`):
    another node's announcement meanwhile is refused, named in a throttled line.
    Thread-safe."""

    def __init__(self, who, clock=None):
        self.who = who
        self.gate = SenderGate(who, 'a server')
        self.leases = Leases()
        self._clock = clock or rospy.get_time
        self._lock = threading.Lock()
        self._uri = {}         # server -> the probe uri its holder announced
        self._refused = Throttle(5.0)
        self.sub = None

    def start(self):
        self.sub = rospy.Subscriber(fleet(names.ANNOUNCE_TOPIC), ServerAnnouncement,
                                    self.on_announcement, queue_size=100)

    def on_announcement(self, msg):
        if not self.gate.admits(msg, 'a server announcement'):
            return
        node, now = publisher_of(msg), self._clock()
        try:
            _changed, holder = self.leases.renew(msg.server_id, node, now, msg.lease)
        except ValueError:
            return
        if holder is not None:
            warn(self._refused, '%s: ignored an announcement of server %d by %s: the id is '
                 '%s\'s until it leaves or its lease ends'
                 % (self.who, msg.server_id, node, holder))
            return
        with self._lock:
            if msg.lease > 0 and msg.probe_uri:
                self._uri[msg.server_id] = msg.probe_uri
            else:
                self._uri.pop(msg.server_id, None)

    def of(self, server):
        """``(probe uri, node)`` of server ``server``'s holder while its lease lasts, or
        None."""
        node = self.leases.holder(server, self._clock())
        with self._lock:
            uri = self._uri.get(server)
        return (uri, node) if node is not None and uri else None
