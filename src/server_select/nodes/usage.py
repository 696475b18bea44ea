"""Measures the CPU% and RSS of running ROS nodes (looked up by name at the master)."""

import rosgraph
import rospy

from server_select.core.util.procs import measure
from server_select.core.util.tables import markdown_table
from server_select.ros.graph import node_pid
from server_select.ros.node import end_parent_launch, param
from server_select.ros.runner import run


class UsageNode(object):
    """Prints one Markdown table of CPU% and RSS per node, measured over ``~duration``.

    :ROS Parameters:
        - ``~nodes`` (list of str, required): node names, e.g. ``[/manager, /server1]``.
        - ``~duration`` (s, 20.0), ``~delay`` (s, 5.0): wait ``~delay``, then measure.
        - ``~end_launch`` (false): then end the roslaunch that started it, as Ctrl-C would.
    """

    def __init__(self):
        self.nodes = [rospy.resolve_name(n) for n in param('nodes')]
        self.duration = param('duration', default=20.0)
        self.delay = param('delay')
        self.end_launch = param('end_launch')

    def start(self):
        self.timer = rospy.Timer(rospy.Duration(self.delay), self.measure, oneshot=True)

    def measure(self, _event):
        pids = {}
        for node in self.nodes:
            try:
                pids[node] = node_pid(node, rospy.get_name())
            except (rosgraph.MasterError, OSError) as error:
                rospy.logerr('usage: cannot find the pid of %s: %s', node, error)
        usage = measure(list(pids.values()), self.duration)
        rows = []
        for node, pid in pids.items():
            u = usage.get(pid)
            rows.append((node, 'exited', '-', '-') if u is None else (
                node, '%.2f' % u['cpu_percent'], '%.1f' % u['rss_mb'], u['threads']))
        table = markdown_table(('node', 'CPU %% (over %.0f s)' % self.duration, 'RSS MiB',
                                'threads'), rows)
        print('\nnode usage\n\n' + table + '\n', flush=True)
        if not (self.end_launch and end_parent_launch()):
            rospy.signal_shutdown('usage measured')


def main():
    run('usage', UsageNode)
