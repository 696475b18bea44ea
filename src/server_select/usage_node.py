"""Measures the CPU% and RSS of running ROS nodes (looked up by name at the master)."""

import xmlrpc.client

import rosgraph
import rospy

from server_select.node_util import get_param, run
from server_select.params import ParamError, parse_positive
from server_select.usage import measure


def node_pid(master, node_name):
    """The pid of ``node_name`` (its XML-RPC getPid)."""
    uri = master.lookupNode(node_name)
    code, message, pid = xmlrpc.client.ServerProxy(uri).getPid(rospy.get_name())
    if code != 1:
        raise rosgraph.MasterError('getPid of %s: %s' % (node_name, message))
    return pid


class UsageNode(object):
    """Prints one Markdown table of CPU% and RSS per node, measured over ``~duration``.

    :ROS Parameters:
        - ``~nodes`` (list of str, required): node names, e.g. ``[/manager, /server1]``.
        - ``~duration`` (s, 20.0), ``~delay`` (s, 5.0): wait ``~delay``, then measure.
    """

    def __init__(self):
        nodes = get_param('~nodes')
        if isinstance(nodes, str):
            nodes = nodes.replace(',', ' ').split()
        if not nodes or not all(isinstance(n, str) for n in nodes):
            raise ParamError('~nodes: expected a list of node names, got %r' % (nodes,))
        self.nodes = [rospy.resolve_name(n) for n in nodes]
        self.duration = parse_positive('~duration', get_param('~duration', 20.0))
        self.delay = parse_positive('~delay', get_param('~delay', 5.0))
        self.timer = rospy.Timer(rospy.Duration(self.delay), self.run, oneshot=True)

    def run(self, _event):
        master = rosgraph.Master(rospy.get_name())
        pids = {}
        for node in self.nodes:
            try:
                pids[node] = node_pid(master, node)
            except (rosgraph.MasterError, OSError) as error:
                rospy.logerr('usage: cannot find the pid of %s: %s', node, error)
        usage = measure(list(pids.values()), self.duration)
        lines = ['| node | CPU %% (over %.0f s) | RSS MiB | threads |' % self.duration,
                 '|---|---|---|---|']
        for node, pid in pids.items():
            u = usage.get(pid)
            if u is None:
                lines.append('| %s | exited | - | - |' % node)
            else:
                lines.append('| %s | %.2f | %.1f | %d |' % (
                    node, u['cpu_percent'], u['rss_mb'], u['threads']))
        print('\nnode usage\n\n' + '\n'.join(lines) + '\n', flush=True)
        rospy.signal_shutdown('usage measured')


def main():
    run('usage', UsageNode)
