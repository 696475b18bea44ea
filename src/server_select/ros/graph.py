"""Look-ups in the ROS graph: which process a node is, who published a message, who
provides a service, who hears a publisher."""

import threading
import time
import xmlrpc.client

import rosgraph

from server_select.core.util import tcp


class _TimedTransport(xmlrpc.client.Transport):
    def __init__(self, timeout):
        super(_TimedTransport, self).__init__()
        self.timeout = timeout

    def make_connection(self, host):
        connection = super(_TimedTransport, self).make_connection(host)
        connection.timeout = self.timeout
        return connection


def service_uri(name, caller_id, timeout):
    """The URI the master lists for service ``name``, asked with a deadline of ``timeout``
    s (rospy's own lookup has none); rosgraph.MasterError if it lists none, OSError or
    xmlrpc.client.Error when the master does not answer in time."""
    master = xmlrpc.client.ServerProxy(rosgraph.get_master_uri(),
                                       transport=_TimedTransport(timeout))
    code, message, uri = master.lookupService(caller_id, name)
    if code != 1:
        raise rosgraph.MasterError('service [%s] unavailable: %s' % (name, message))
    return uri


def node_pid(node_name, caller_id='/server_select_graph', master=None, timeout=5.0):
    """The pid of ``node_name`` (its XML-RPC ``getPid``); rosgraph.MasterError if unknown,
    OSError when the node does not answer within ``timeout`` s (stopped or hung)."""
    master = master or rosgraph.Master(caller_id)
    uri = master.lookupNode(node_name)
    proxy = xmlrpc.client.ServerProxy(uri, transport=_TimedTransport(timeout))
    code, message, pid = proxy.getPid(caller_id)
    if code != 1:
        raise rosgraph.MasterError('getPid of %s: %s' % (node_name, message))
    return pid


class Liveness(object):
    """``alive(node)``: whether ``node`` answers its XML-RPC API (a node killed without a word
    stays registered at the master, but answers nothing); asked at most once every
    ``period`` s per node, the answer kept meanwhile."""

    def __init__(self, period=1.0, timeout=1.0, clock=time.monotonic):
        self.period, self.timeout, self._clock = period, timeout, clock
        self._lock = threading.Lock()
        self._known = {}          # node -> (asked at, alive)

    def __call__(self, node):
        now = self._clock()
        with self._lock:
            known = self._known.get(node)
        if known is not None and now - known[0] < self.period:
            return known[1]
        try:
            node_pid(node, timeout=self.timeout)
            alive = True
        except (rosgraph.MasterError, OSError):
            alive = False
        with self._lock:
            self._known[node] = (now, alive)
        return alive


def hearing(pub):
    """The nodes connected to ``pub`` (rospy names a connection by its subscriber)."""
    return set(c.endpoint_id for c in list(pub.impl.connections))


def stalled(pub):
    """The connections of ``pub`` (rospy's, each naming its subscriber node in
    ``endpoint_id``) holding data TCP retransmits only every second or less often
    (:func:`server_select.core.util.tcp.stalled`: it lived through an outage with a
    message in flight, and what is written to it waits for the next try)."""
    impl = getattr(pub, 'impl', None)
    return [c for c in list(impl.connections if impl is not None else ())
            if tcp.stalled(getattr(c, 'socket', None))]


def _subscriptions(caller_id):
    """``{topic: [subscriber nodes]}`` as the master lists them (None: it is away)."""
    try:
        return dict(rosgraph.Master(caller_id).getSystemState()[1])
    except (rosgraph.MasterError, OSError):
        return None


def subscribers(topic, caller_id):
    """The nodes the master lists as subscribers of ``topic`` (none when it is away)."""
    return set((_subscriptions(caller_id) or {}).get(topic, ()))


def unheard(nodes, first, others, caller_id):
    """The nodes of ``nodes`` that do not hear yet what they listen to: the publisher
    ``first`` (each must), and those of the publishers ``others`` whose topics the master
    says they subscribe to."""
    missing = [n for n in nodes if n not in hearing(first)]
    if missing or not others:
        return missing
    listed = _subscriptions(caller_id)
    if listed is None:
        return list(nodes)      # the master is away: nothing is known to be heard
    return [n for n in nodes if any(n in listed.get(p.resolved_name, ())
                                    and n not in hearing(p) for p in others)]


def publisher_of(msg):
    """The node that published ``msg`` (its connection's caller id), or '?'."""
    return (getattr(msg, '_connection_header', None) or {}).get('callerid', '?')


class ServiceProviders(object):
    """Which node provides each service, as the master says; looked up again at most every
    ``period`` s when asked to (a server may have been restarted elsewhere)."""

    def __init__(self, caller_id, period=1.0, clock=time.monotonic, system_state=None):
        self.period, self._clock = period, clock
        self._system_state = system_state or (
            lambda: rosgraph.Master(caller_id).getSystemState())
        self._lock = threading.Lock()
        self._nodes = {}
        self._looked_up = -float('inf')

    def node(self, service, refresh=False):
        """The node providing resolved ``service`` (None if unknown). The master is asked
        again when ``refresh`` or the service is unknown, at most every ``period`` s."""
        with self._lock:
            due = self._clock() - self._looked_up >= self.period
            if due and (refresh or service not in self._nodes):
                self._looked_up = self._clock()
                try:
                    _, _, services = self._system_state()
                    self._nodes = dict((name, nodes[0]) for name, nodes in services if nodes)
                except (rosgraph.MasterError, OSError):
                    pass   # the master is away: keep what was known
            return self._nodes.get(service)
