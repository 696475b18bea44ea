"""Calls to a testbed's master, and to its nodes, from this process: the master listens in
the manager's network namespace, which this host's own does not reach, so each call is made
from one thread moved into that namespace (no rospy: rosgraph's XML-RPC client)."""

import concurrent.futures
import ctypes
import os
import xmlrpc.client

import rosgraph

from server_select.ros.graph import node_pid

CALLER = '/testbed'         # the caller id of these calls
CLONE_NEWNET = 0x40000000


def _enter_netns(netns):
    """Move the calling thread into network namespace ``netns`` (its address space)."""
    libc = ctypes.CDLL(None, use_errno=True)
    fd = os.open('/run/netns/%s' % netns, os.O_RDONLY)
    try:
        if libc.setns(fd, CLONE_NEWNET) != 0:
            raise OSError(ctypes.get_errno(), 'setns %s' % netns)
    finally:
        os.close(fd)


class MasterLink(object):
    """Calls to the master at ``uri`` (and to nodes) from a thread inside ``netns``; a
    context manager that ends the thread on exit."""

    def __init__(self, netns, uri):
        self.uri = uri
        self.pool = concurrent.futures.ThreadPoolExecutor(1, initializer=_enter_netns,
                                                          initargs=(netns,))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def call(self, function, *args, timeout=10.0):
        return self.pool.submit(function, *args).result(timeout)

    def _ask(self, question, failed):
        """``question(master)`` from the namespace's thread; ``failed`` when the master or
        the node asked does not answer."""
        def ask():
            try:
                return question(rosgraph.Master(CALLER, master_uri=self.uri))
            except (OSError, rosgraph.MasterError, xmlrpc.client.Error):
                return failed
        return self.call(ask)

    def pid(self, node):
        """The pid ``node`` says it has, None when the master or the node does not answer
        (a stopped node within 2 s)."""
        return self._ask(lambda master: node_pid(node, CALLER, master, timeout=2.0), None)

    def nodes(self):
        """The names of the nodes registered with the master (empty when it does not
        answer)."""
        def registered(master):
            return set(node for kind in master.getSystemState() for _, nodes in kind
                       for node in nodes)
        return self._ask(registered, set())

    def bus_info(self, node):
        """``node``'s connections (getBusInfo: id, peer, direction, transport, topic, ...);
        [] when it does not answer."""
        def connections(master):
            code, _, info = xmlrpc.client.ServerProxy(master.lookupNode(node)).getBusInfo(CALLER)
            return info if code == 1 else []
        return self._ask(connections, [])

    def master_pid(self):
        """The master's pid, None when it does not answer."""
        return self._ask(lambda master: master.getPid(), None)

    def up(self):
        """Whether the master answers."""
        return self.master_pid() is not None

    def close(self):
        self.pool.shutdown(wait=False)
