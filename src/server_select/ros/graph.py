"""Look-ups in the ROS graph: which process a node is."""

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
