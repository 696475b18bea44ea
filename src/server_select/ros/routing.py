"""How tasks reach servers and results reach robots: broadcast (the paper) or direct.

``broadcast``: every task of a kind on one fleet topic (``data``), which every server
receives and all but the addressed one drop; every result on one topic (``processed_data``)
that every robot receives. ``direct`` (fleet profile): a task on the addressed server's own
topic (``server_<s>/data``), its result on the sending robot's own topic
(``robot_<r>/processed_data``), so bytes on each link do not grow with the number of
servers or robots.
"""

import threading

import rospy

from server_select.core.config import names
from server_select.core.util import tcp
from server_select.core.util.lasting import Lasting
from server_select.ros.graph import hearing, stalled
from server_select.ros.node import fleet, unregister

# s a server that answers probes (so it subscribes to our task topic) may go without hearing
# our task publisher before the publisher is made anew. rospy connects a subscriber once,
# when the master names the publisher, and does not try again when that connection is lost
# as it is made (two of the master's updates at once, or a publisher too busy to answer).
DEAF_GRACE = 5.0


class BroadcastRoute(object):
    """Robot side, paper layout: one task topic, one result topic per task kind."""

    def __init__(self, robot_id, kind, on_result):
        self.kind, self.on_result = kind, on_result
        self._lock = threading.Lock()
        self.pubs = {}            # None -> the one task publisher (a dict for renew())
        self.sub = None
        self.deaf = Lasting(DEAF_GRACE)

    def _pub(self):
        pub = self.pubs.get(None)
        if pub is None:
            pub = self.pubs[None] = rospy.Publisher(
                fleet(self.kind.task_topic), self.kind.task_type, queue_size=100)
        return pub

    def start(self):
        with self._lock:
            self._pub()
        self.sub = _results(fleet(self.kind.result_topic), self.kind, self.on_result)

    def publish(self, request, _server):
        with self._lock:      # (not while heard() makes it anew)
            self._pub().publish(request)

    def heard(self, server, node=None):
        """``server`` answered a probe: the publisher is made anew when the server's node
        ``node`` has not heard it for DEAF_GRACE s (every server then connects again); the
        nodes it was made anew for. A stalled connection is kept, as the paper's robot
        kept it (one publisher for every server: making it anew drops every server's)."""
        with self._lock:
            deaf = node is not None and node not in hearing(self._pub())
            if not self.deaf.held(server, deaf):
                return []
            return renew(self.pubs, None, self._pub, [node])

    def publishers(self):
        with self._lock:
            return [self._pub()]

    def wired(self, _server, node=None):
        """Whether our result topic hears a server and our task topic reaches ``node`` (the
        server's node name; None: unknown, any server will do). A robot started again under
        its name is connected to one server after another: a task sent before the selected
        one is connected is lost to it."""
        with self._lock:
            pub = self._pub()
        if not (pub.get_num_connections() > 0 and self.sub.get_num_connections() > 0):
            return False
        # rospy names a publisher's connection by its subscriber's caller id
        return node is None or node in hearing(pub)

    def add(self, server):
        pass

    def remove(self, server):
        self.deaf.forget(server)

    def shutdown(self):
        with self._lock:
            pubs, self.pubs = list(self.pubs.values()), {}
        for endpoint in pubs + [self.sub]:
            if endpoint is not None:
                unregister(endpoint)


class DirectRoute(object):
    """Robot side, fleet layout: a task publisher per server, one result topic of its own."""

    def __init__(self, robot_id, kind, on_result):
        self.robot_id, self.kind, self.on_result = robot_id, kind, on_result
        self._lock = threading.Lock()
        self.pubs = {}
        self.sub = None
        self.deaf = Lasting(DEAF_GRACE)

    def start(self):
        self.sub = _results(fleet(names.robot_topic(self.robot_id, self.kind.result_topic)),
                            self.kind, self.on_result)

    def _pub(self, server):
        """``server``'s task publisher, made now if there is none (the lock held)."""
        pub = self.pubs.get(server)
        if pub is None:
            pub = self.pubs[server] = rospy.Publisher(
                fleet(names.server_topic(server, self.kind.task_topic)),
                self.kind.task_type, queue_size=100)
        return pub

    def publish(self, request, server):
        with self._lock:      # (not while heard() makes it anew)
            self._pub(server).publish(request)

    def heard(self, server, node=None):
        """``server`` answered a probe: when its task connection is stalled
        (:func:`~server_select.ros.graph.stalled`), or it has not connected for
        DEAF_GRACE s, the publisher is made anew so that the server connects again, and
        the subscribers it names are returned. The server's ``node`` itself must hear it:
        a recorder (``rosbag record``) connected to the topic is no server."""
        with self._lock:
            pub = self._pub(server)
            deaf = node not in hearing(pub) if node else pub.get_num_connections() == 0
            return renew(self.pubs, server, lambda: self._pub(server),
                         [node or 'server %d' % server] if self.deaf.held(server, deaf)
                         else [])

    def publishers(self):
        with self._lock:
            return list(self.pubs.values())

    def wired(self, server, _node=None):
        # The server makes our result publisher at our first task and waits for us to
        # connect (ResultRoutes), so only the task side can be checked beforehand.
        with self._lock:
            return self._pub(server).get_num_connections() > 0

    def add(self, server):
        with self._lock:
            self._pub(server)

    def remove(self, server):
        self.deaf.forget(server)
        with self._lock:
            pub = self.pubs.pop(server, None)
        if pub is not None:
            unregister(pub)

    def shutdown(self):
        with self._lock:
            pubs, self.pubs = list(self.pubs.values()), {}
        for endpoint in pubs + [self.sub]:
            if endpoint is not None:
                unregister(endpoint)


ROUTES = {'broadcast': BroadcastRoute, 'direct': DirectRoute}


def renew(pubs, key, make, deaf=()):
    """Unregister ``pubs[key]`` and ``make()`` it again when a connection of it is stalled
    or ``deaf`` names subscribers that do not hear it; the stalled subscribers' nodes and
    ``deaf``, or [] (the caller holds the lock guarding ``pubs``). Its connections close
    with a reset, so that their subscribers drop them at once (one that still held it
    would not connect again), and the new registration has the master tell them to
    connect anew."""
    pub = pubs.get(key)
    nodes = [c.endpoint_id for c in stalled(pub)] + list(deaf) if pub is not None else []
    if nodes:
        for connection in list(pub.impl.connections):
            tcp.reset_on_close(getattr(connection, 'socket', None))
        del pubs[key]
        unregister(pub)
        make()
    return nodes


def made_anew(pub, make, deaf):
    """:func:`renew` for one publisher ``pub`` (``make()`` makes it again) whose ``deaf``
    subscribers do not hear it: ``(the publisher now, the nodes it was made anew for)``."""
    pubs = {None: pub}
    nodes = renew(pubs, None, lambda: pubs.__setitem__(None, make()), deaf)
    return pubs[None], nodes


def kind_name(kind):
    return getattr(kind, 'kind', kind.task_topic)


def _results(topic, kind, callback):
    return rospy.Subscriber(topic, kind.result_type, callback, queue_size=100,
                            tcp_nodelay=True, buff_size=1 << 24)
