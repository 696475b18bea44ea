"""Server groups (no rospy): which group each robot belongs to, by representative latency.

The paper's proposal for many servers: groups of servers, each with a manager of its own,
and a top manager that assigns each robot to a group. A robot probes its own group's
servers and the representative (first server) of every other group, so its probes grow
with the group size plus the number of groups, not with all servers. The top manager
compares a robot's windowed mean round trip to each group's representative and moves the
robot to a nearer group only when that one is nearer by more than ``margin`` s.
"""

import threading

import yaml

from server_select.core.config.params import ParamError, parse_id, parse_id_list
from server_select.core.ranking.window import LatencyWindow


def parse_groups(name, value):
    """``{group id: [server ids]}`` from a mapping or its YAML text; groups are non-empty
    and share no server."""
    if isinstance(value, str):
        try:
            value = yaml.safe_load(value)
        except yaml.YAMLError as error:
            raise ParamError('%s: not YAML: %s' % (name, error))
    if not isinstance(value, dict) or not value:
        raise ParamError('%s: expected a mapping {group id: [server ids]}, got %r'
                         % (name, value))
    groups, seen = {}, {}
    for key, servers in value.items():
        group = parse_id(name, key)
        servers = parse_id_list('%s[%s]' % (name, key), servers)
        for server in servers:
            if server in seen:
                raise ParamError('%s: server %d is in groups %d and %d'
                                 % (name, server, seen[server], group))
            seen[server] = group
        groups[group] = servers
    return dict(sorted(groups.items()))


def representatives(groups):
    """``{representative server: group}``: the first server of each group."""
    return dict((servers[0], group) for group, servers in groups.items())


def probe_set(groups, group):
    """The servers a robot of ``group`` probes (None: not assigned yet): its group's servers
    and every group's representative."""
    wanted = set(s[0] for s in groups.values())
    if group in groups:
        wanted.update(groups[group])
    return wanted


class GroupAssigner(object):
    """Robots to groups by the mean round trip to each group's representative."""

    def __init__(self, groups, window, margin):
        self.groups = groups
        self.margin = float(margin)
        self.reps = representatives(groups)
        self.window = LatencyWindow(window)
        self._lock = threading.Lock()
        self.assigned = {}        # robot -> group

    def add(self, robot, server, now, ok, rtt):
        """A sample of ``robot``; only representatives count (ValueError for a bad rtt)."""
        group = self.reps.get(server)
        if group is not None:
            self.window.add(robot, group, now, ok, rtt)

    def assign(self, robot, now):
        """Update ``robot``'s group; True when it changed."""
        means = dict((g, self.window.stats(robot, g, now).mean) for g in self.groups)
        means = dict((g, m) for g, m in means.items() if m is not None)
        if not means:
            return False
        best = min(sorted(means), key=lambda g: means[g])    # ties to the lower group id
        with self._lock:
            current = self.assigned.get(robot)
            if current in means and means[current] - means[best] <= self.margin:
                return False
            if current == best:
                return False
            self.assigned[robot] = best
            return True

    def table(self):
        with self._lock:
            return sorted(self.assigned.items())
