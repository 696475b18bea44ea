"""Manager: ranks each robot's servers by mean probe latency and publishes the choice."""

import threading

import rospy

from server_select.core.config import names
from server_select.core.config.params import ParamError
from server_select.core.ranking.policy import Chooser, from_params
from server_select.core.manager.sample_rankings import SampleRankings
from server_select.core.trust.senders import node_pattern_of
from server_select.core.manager.view_rankings import ViewRankings
from server_select.msg import LatencySample, LatencySamples, RobotRanking
from server_select.ros.flags import FlagPublisher
from server_select.ros.membership import GroupAssignmentsListener, ServerRegistry
from server_select.ros.node import fleet, param
from server_select.ros.runner import run
from server_select.ros.intake import SampleIntake
from server_select.ros.senders import robot_senders


SLICES = 10     # the periodic flags go out in this many slices of the robots
STALE_VIEWS = 3.0   # a robot's own ranking counts for this many of its periods


class ManagerNode(object):
    """The selection manager of paper 1.

    Keeps the samples of the last ``~window`` seconds of every (robot, server) pair, ranks
    each robot's servers by mean round trip (stable sort, ties to the lower id, servers
    without a successful sample excluded) and publishes one ``server_select_flag`` per
    robot every ``1/~publish_rate`` s, and at once when a robot's selected server or the set
    of servers it ranks changes. A sample costs O(1); a robot is ranked again only when a
    sample may change its flag (at most once per batch), when the last good sample of any
    of its servers leaves the window (checked every ``1/~update_rate`` s: a dead server
    leaves every ranking, not only those that select it, within ``~window`` and one
    check of its last answer), and with each periodic flag. Window times are the manager's
    receive times: robot and manager clocks are not shared. A robot gets no flag before its first
    sample (a restarted manager does not publish an empty ranking over a robot's working
    choice). Samples claiming another pair, with an impossible round trip, or not
    published by robot r (``~robot_node``: by default the first node that sent for r, while
    it answers, whatever its name or namespace) are ignored with a throttled warning naming
    the publisher.

    :ROS Parameters: (all, with both profiles' defaults: docs/parameters.md)
        - ``~robots``, ``~servers`` (required in the paper profile; fleet: whoever sends
          samples, whatever they probe); ``~profile``; ``~fleet_ns``; ``~robot_node``
        - ``~sample_stream``: samples per pair on ``latency_R<r>S<s>``, batches on
          ``latency_samples`` (``robot``), or each robot's own ranking on
          ``robot_rankings`` (``view``, the fleet's: this node keeps the policy's state
          and the flags; a ranking older than 3 / ``~view_rate`` s counts as none)
        - ``~flag_stream``: every flag on ``server_select_flag`` (``shared``), or each on
          its robot's own latched ``robot_<r>/server_select_flag`` (``robot``)
        - ``~discover``: list the servers that announce themselves (leases of 3 x
          ``~announce_period``) on ``fleet_servers``
        - ``~window``, ``~publish_rate``, ``~update_rate``, ``~policy`` and its options
          (``core/ranking/policy.py``), ``~passive``, ``~task_memory``
        - ``~group``: a grouped deployment's manager of that group, for the robots
          ``~top_manager_node`` assigns to it
    :ROS Subscribers:
        - ``latency_R<r>S<s>`` (server_select/LatencySample) for every robot r and server s,
          or ``latency_samples`` (server_select/LatencySamples), or ``robot_rankings``
          (server_select/RobotRanking); ``task_samples``
          (server_select/LatencySamples, ``~passive``); ``server_announcements``
          (server_select/ServerAnnouncement, ``~discover``).
    :ROS Publishers:
        - ``server_select_flag`` (server_select/SelectionFlag); (fleet) each robot's
          ``robot_<r>/server_select_flag``
        - ``fleet_servers`` (server_select/FleetServers, latched; with ``~discover``)
    """
    SEAL_ROLE = 'manager'  # what it signs as with a fleet key (core/trust/seal.py)
    DIAGNOSTICS = 'manager'  # its statuses on /diagnostics (ros/diagnostics.py)

    MASTER_WATCHER = True     # checks for a restarted roscore and tells the fleet

    def __init__(self):
        self.stream = param('sample_stream')
        self.policy, statistic = from_params(param)
        if self.stream == 'view':    # the robots rank for themselves
            self.rankings = ViewRankings(STALE_VIEWS / param('view_rate'), param('robots'),
                                         param('servers'))
        else:
            self.rankings = SampleRankings(param('window'), param('robots'), param('servers'),
                                           statistic, param('fail_fast'),
                                           self.policy.robust,
                                           param('task_memory') if param('passive') else 0.0,
                                           param('window_samples'), param('window_max'))
        self.passive = param('passive') and self.stream != 'view'  # (views hold the tasks)
        for name in ('robots', 'servers'):
            if self.stream == 'pair' and not getattr(self.rankings, 'fixed_' + name):
                raise ParamError('~%s: expected a non-empty list of ids (an empty one needs '
                                 '~sample_stream robot: one topic per pair)' % name)
        self.publish_rate = param('publish_rate')
        self.update_rate = param('update_rate')
        self._locks = {}          # robot -> lock of its ranking and flag
        self._choosers = {}       # robot -> its Chooser (the policy's state)
        self._slice = 0
        self.group = param('group')       # grouped: robots get their servers elsewhere
        self.discovery = ServerRegistry(param('announce_period'), self.on_leave) \
            if param('discover') and self.group is None else None
        self.assignments = None
        if self.group is not None:      # a group's manager: members from the top manager
            self.rankings.set_members([], [])
            self.assignments = GroupAssignmentsListener(
                param('top_manager_node') or '/top_manager', self.on_assignments,
                'manager of group %d' % self.group)
        self.intake = SampleIntake(self.rankings, robot_senders(
            'manager', param('robot_node'), robot_node_hint), self.group,
            lambda robot: self.update(robot, only_on_change=True))
        self.flags = FlagPublisher('manager' if self.group is None else
                                   'manager of group %d' % self.group,
                                   max(100, 4 * len(self.rankings.fixed_robots)))
        self.sample_subs = []
        self.timers = []

    def start(self):
        if self.stream == 'pair':
            self.sample_subs = [
                rospy.Subscriber(fleet(names.sample_topic(r, s)), LatencySample,
                                 self.intake.on_sample, callback_args=(r, s), queue_size=100,
                                 tcp_nodelay=True)
                for r in self.rankings.fixed_robots for s in self.rankings.fixed_servers]
        elif self.stream == 'view':
            self.sample_subs = [rospy.Subscriber(fleet(names.RANKINGS_TOPIC), RobotRanking,
                                                 self.intake.on_view, queue_size=1000,
                                                 tcp_nodelay=True)]
        else:
            self.sample_subs = [rospy.Subscriber(fleet(names.SAMPLES_TOPIC), LatencySamples,
                                                 self.intake.on_batch, queue_size=1000,
                                                 tcp_nodelay=True)]
        if self.passive:      # answered tasks: samples of what the robots really get
            self.sample_subs.append(rospy.Subscriber(
                fleet(names.TASK_SAMPLES_TOPIC), LatencySamples, self.intake.on_batch,
                callback_args=names.TASK_SAMPLES_TOPIC, queue_size=1000, tcp_nodelay=True))
        for part in (self.discovery, self.assignments):
            if part is not None:
                part.start()
        self.timers = [
            rospy.Timer(rospy.Duration(1.0 / (self.publish_rate * SLICES)), self.on_periodic),
            rospy.Timer(rospy.Duration(1.0 / self.update_rate), self.on_check)]
        rospy.loginfo('manager: robots %s, servers %s, policy %s, %s%s',
                      self.rankings.fixed_robots or 'as they come',
                      self.rankings.fixed_servers or 'as probed', self.policy.describe(),
                      self.describe_input(),
                      ' and answered tasks' if self.passive else '')

    def describe_input(self):
        if self.stream == 'view':
            return "the robots' own rankings"
        return 'window %.3g s of %s, samples %s' % (
            self.rankings.window.window, self.rankings.window.statistic,
            'per pair' if self.stream == 'pair' else 'in one batch per robot round')

    def on_assignments(self, groups, assigned):
        """The top manager's table: this group's servers and robots."""
        if self.group not in groups:
            rospy.logwarn_throttle(30.0, 'manager of group %d: the top manager has no group %d '
                                   '(groups %s)' % (self.group, self.group, sorted(groups)))
        robots = [r for r, g in assigned.items() if g == self.group]
        self.rankings.set_members(robots, groups.get(self.group, []))

    def on_leave(self, servers):
        """Servers left the fleet (``~discover``): out of every ranking at once."""
        robots = set()
        for server in servers:
            robots.update(self.rankings.forget_server(server))
        for robot in sorted(robots):
            self.update(robot, only_on_change=True)

    def on_periodic(self, _event):
        """Every robot's flag once per ``1/~publish_rate`` s, a slice of the robots at a
        time, so that re-ranking hundreds of robots never holds up a flag a sample asks
        for."""
        self._slice = (self._slice + 1) % SLICES
        for index, robot in enumerate(self.rankings.robots()):
            if index % SLICES == self._slice and self.rankings.heard(robot):
                self.update(robot, only_on_change=False)

    def on_check(self, _event):
        """Between flags: re-rank the robots of which a server has no good sample left."""
        for robot in self.rankings.departures(rospy.get_time()):
            self.update(robot, only_on_change=True)

    def update(self, robot, only_on_change):
        """Rank ``robot``'s servers now; publish unless unchanged and ``only_on_change``.

        One update of a robot at a time: samples arrive on many threads, and a ranking
        computed before another thread's sample must not be published after the newer one."""
        with self._locks.setdefault(robot, threading.Lock()):
            now = rospy.get_time()
            ranking = self.rankings.rank(robot, now)
            chooser = self._chooser(robot)
            if self.flags.offer(robot, ranking, only_on_change,
                                lambda previous: chooser.choose(ranking, now, previous),
                                lambda: chooser.reason):
                self.rankings.selected(robot, self.flags.selected(robot))

    def _chooser(self, robot):
        """The policy's state for ``robot``."""
        chooser = self._choosers.get(robot)
        if chooser is None:
            chooser = self._choosers.setdefault(
                robot, Chooser(self.policy))
        return chooser


def robot_node_hint(sender, robot):
    """The fix for a robot's node that ``~robot_node`` does not admit."""
    pattern = node_pattern_of(sender, robot)
    return 'if %s is robot %s, start the manager with robot_node:=%s' % (
        sender, robot, pattern) if pattern else None


def main():
    run('manager', ManagerNode)
