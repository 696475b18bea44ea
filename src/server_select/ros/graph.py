"""Look-ups in the ROS graph: which process a node is, who published a message, who
provides a service."""

import threading
import time
import xmlrpc.client

import rosgraph


def node_pid(node_name, caller_id='/server_select_graph', master=None):
    """The pid of ``node_name`` (its XML-RPC ``getPid``); rosgraph.MasterError if unknown."""
    master = master or rosgraph.Master(caller_id)
    uri = master.lookupNode(node_name)
    code, message, pid = xmlrpc.client.ServerProxy(uri).getPid(caller_id)
    if code != 1:
        raise rosgraph.MasterError('getPid of %s: %s' % (node_name, message))
    return pid


def publisher_of(msg):
    """The node that published ``msg`` (its connection's caller id), or '?'."""
    return (getattr(msg, '_connection_header', None) or {}).get('callerid', '?')


class ServiceProviders(object):
    """Which node provides each service, as the master says; looked up again at most every
    ``period`` s when asked to (a server may have been restarted elsewhere)."""

    def __init__(self, caller_id, period=1.0, clock=time.monotonic):
        self.caller_id, self.period, self._clock = caller_id, period, clock
        self._lock = threading.Lock()
        self._nodes = {}
        self._looked_up = -float('inf')

    def node(self, service, refresh=False):
        """The node providing resolved ``service`` (None if none, or the master is away)."""
        with self._lock:
            stale = refresh and self._clock() - self._looked_up >= self.period
            if service in self._nodes and not stale:
                return self._nodes[service]
            if stale or service not in self._nodes:
                self._looked_up = self._clock()
                try:
                    _, _, services = rosgraph.Master(self.caller_id).getSystemState()
                except (rosgraph.MasterError, OSError):
                    return self._nodes.get(service)
                self._nodes = dict((name, nodes[0]) for name, nodes in services if nodes)
            return self._nodes.get(service)
