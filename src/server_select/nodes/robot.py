"""Robot: probes every server, follows the manager's selection and sends tasks."""

import time

import rospy

from server_select.core.config import names
from server_select.core.config.params import ParamError
from server_select.core.flow.task_flow import LOCAL, NO_SERVER
from server_select.core.robot.robot import Robot
from server_select.msg import SelectionFlag
from server_select.ros.camera import TopicSource
from server_select.ros.flags import flag_topic
from server_select.ros.graph import ServiceProviders, publisher_of
from server_select.ros.live_tuning import LiveTuning
from server_select.ros.membership import GroupFollower, ServerAnnouncements
from server_select.ros.robot_parts import RobotWire, fixed_server, not_in_force
from server_select.ros.node import fleet, param
from server_select.ros.runner import run
from server_select.ros.senders import SenderGate
from server_select.tasks.kinds import stream_kinds
from server_select.ros.view import RankingSender
from server_select.tasks.image import Frames


class RobotNode(object):
    """A robot of the fleet: the package's :class:`~server_select.core.robot.robot.Robot`
    (every decision: probes, selection, health, load, task streams) on rospy's wire.

    Tasks go to the selected server (``~mode`` ``select``), to ``~fixed_server``
    (``fixed``, the paper's baseline), or are processed by the robot itself (``local``).
    Two streams, each optional: sort tasks (``~task_size`` random int32 at ``~task_rate``)
    and camera frames (``~image_source`` at ``~frame_rate``). Each task ends in exactly one
    ``task_report``: a checked result, an error result, or a timeout after
    ``~task_timeout``. With camera frames it takes part in the cooperative search.

    :ROS Parameters: (all, with defaults: docs/parameters.md, made from ``core/settings.py``)
        - ``~robot_id``; ``~servers`` (may be empty with ``~discover`` or
          ``~top_manager_node``); ``~profile``, ``~routing``, ``~sample_stream``
        - ``~mode``, ``~fixed_server``, ``~probe_rate`` or ``~contender_rate`` (adaptive), the task
          streams' (``~sort_tasks``, ``~task_rate``, ``~image_source`` or
          ``~image_topic``, ``~frame_rate``, ``~task_plugins``, ...), failover, health and
          policy (``~retry_factor``, ``~policy``, ...), ``~passive``, ``~manager_node`` or,
          grouped, ``~group_manager_node``; ``~start_delay``; capacity (``~load_aware``, ...)
    :ROS Publishers:
        - ``latency_R<robot_id>S<s>`` or ``latency_samples`` (fleet); ``task_samples``;
          ``robot_rankings`` (its own ranking, ``~sample_stream view``: fleet)
        - ``data``, ``task_image``, or per server ``server_<s>/data``, ... (fleet)
        - ``task_report`` (server_select/TaskReport), ``found_targets`` (FoundTarget)
    :ROS Subscribers:
        - ``server_select_flag``, or (fleet) its own ``robot_<robot_id>/server_select_flag``;
          ``processed_data``, ``processed_image``, or
          ``robot_<robot_id>/processed_data``, ... (fleet); ``detections``,
          ``found_targets``; ``fleet_servers`` (``~discover``) or ``group_assignments``
    :ROS Services: ``~known_targets`` (KnownTargets); ``~set_parameters`` (dynamic_reconfigure:
        the settings it takes while running, ros/live_tuning.py); calls ``latency_S<s>``
    """
    SEAL_ROLE = 'robot'  # what it signs as with a fleet key (core/trust/seal.py)
    DIAGNOSTICS = 'robot'  # its statuses on /diagnostics (ros/diagnostics.py)

    def __init__(self):
        self.robot_id = param('robot_id')
        servers = param('servers')
        mode = param('mode')
        self.discover = param('discover')
        if not servers and (mode == 'fixed' or not (self.discover or
                                                    param('top_manager_node'))):
            raise ParamError('~servers: expected a non-empty list of ids (an empty one needs '
                             '~discover, and a mode other than fixed)')
        fixed = fixed_server(servers, mode)
        kinds = stream_kinds(self.robot_id, mode, param)
        image = next((k for k, _ in kinds if isinstance(k, Frames)), None)
        self.search = image.search if image else None
        self.camera = image.source if image and isinstance(image.source, TopicSource) else None
        load_aware = param('load_aware') and mode == 'select'
        self.wire = RobotWire(self.robot_id, self.server_node, load_aware)
        self.addresses, self.prober = self.wire.addresses, self.wire.prober
        try:
            self.robot = Robot(self.robot_id, servers, mode, param, kinds, transport=self.wire,
                               events=self.wire, stamp=rospy.Time.now, fixed=fixed,
                               limit=param('tasks'))
        except ValueError as error:
            raise ParamError(str(error))
        self.wire.attach(self.robot)
        self.selection, self.health = self.robot.selection, self.robot.health
        self.policy, self.load = self.robot.policy, self.robot.load
        self.streams = list(self.wire.streams.values())
        self.view = RankingSender(self.robot_id, self.selection, self.policy, param('view_rate'),
                                  manager=lambda: self.manager_node) \
            if param('sample_stream') == 'view' and mode == 'select' else None
        if self.view is not None:       # one check of its ranking per batch of probe answers
            self.view.coalesce, self.prober.after_answers = True, self.view.flush
            # and one at each move, so that the manager's flag names where tasks go now
            self.wire.on_move = lambda: self.view.send(False)
        self.summary_period = param('summary_period')
        manager = param('manager_node')   # None: flags from any node
        self.manager_node = rospy.resolve_name(manager) if manager else None
        self.flag_senders = SenderGate('robot %d' % self.robot_id, 'the manager',
                                       self.manager_node)
        self.providers = ServiceProviders(rospy.get_name())
        top = param('top_manager_node')     # grouped: servers and manager from its table
        self.announcements = GroupFollower(self.robot_id, servers, top, self.on_servers,
                                           self.on_group) if top else ServerAnnouncements(
            servers, self.on_servers, self.manager_node, self.robot_id) if self.discover \
            else None
        self._start_after, self._local_decision = None, False
        self.timers = []
        self.tuning = LiveTuning('robot %d' % self.robot_id, self.robot, param,
                                 after=lambda: [s.pacer.poke() for s in self.streams])
        not_in_force()      # rosparam shows only what this robot uses

    def start(self):
        self._start_after = time.monotonic() + self.robot.start_delay
        self.flag_sub = rospy.Subscriber(flag_topic(self.robot_id, param('flag_stream')),
                                         SelectionFlag, self.on_flag, queue_size=100,
                                         tcp_nodelay=True)
        if self.search is not None:
            self.search.start()
        if self.camera is not None:
            self.camera.start()
        for stream in self.streams:
            stream.start()
        if self.addresses is not None:
            self.addresses.start()
        self.robot.start()      # task topics connected before the first task
        self.prober.start(self.robot)
        for stream in self.streams:
            stream.pace()
        for part in (self.announcements, self.view):
            if part is not None:
                part.start()
        self.tuning.start()     # dynparam set /robot<r> window 3.0 (ros/live_tuning.py)
        self.timers = [rospy.Timer(rospy.Duration(self.summary_period),
                                   lambda _e: rospy.loginfo(self.summary())),
                       rospy.Timer(rospy.Duration(0.5), self.on_decision_timer)]
        rospy.on_shutdown(self.on_shutdown)
        selection = self.selection
        rospy.loginfo('robot %d: mode %s%s, probing servers %s %s, tasks: %s',
                      self.robot_id, selection.mode,
                      ' (server %d)' % selection.fixed_server if selection.mode == 'fixed' else '',
                      self.robot.servers, self.robot.plan.describe(),
                      ', '.join(s.flow.kind for s in self.streams))

    def server_node(self, server, refresh=False):
        """The node that is server ``server``, whose results alone count: with a fleet key
        the one its sealed announcement names, else the master's for its probe service."""
        announced = self.addresses and self.addresses.of(server)
        return announced[1] if announced else self.providers.node(
            fleet(names.probe_service(server)), refresh)

    def on_servers(self, added, removed):
        """Servers joined (candidates once their task topics connect) or left the fleet."""
        for server in added:
            self.robot.add_server(server)
        for server in removed:
            self.robot.remove_server(server)

    def on_group(self, group, servers):
        """Grouped: the top manager put this robot in ``group`` of ``servers``; its
        manager's flags count, and a robot that chooses per task chooses among those."""
        self.manager_node = rospy.resolve_name(param('group_manager_node').format(group=group))
        self.flag_senders.expect(self.manager_node)
        self.selection.restrict(servers)

    def on_flag(self, flag):
        if flag.robot_id != self.robot_id:
            return
        if not self.flag_senders.admits(flag, 'a flag'):
            return
        refused = self.robot.on_flag(flag.robot_id, flag.server_id, flag.ranking)
        if refused:
            rospy.logwarn_throttle(5.0, 'robot %d: ignored a flag of %s: it %s'
                                   % (self.robot_id, publisher_of(flag), refused))

    def on_decision_timer(self, _event):
        self.robot.admit_joined()
        local = self.selection.deciding_locally()
        starting = time.monotonic() < self._start_after + self.selection.manager_timeout
        if local and starting and not self.selection.flagged():
            return   # no flag yet at start-up: nothing to warn about
        if local != self._local_decision:
            self._local_decision = local
            if local:
                rospy.logwarn('robot %d: no fresh flag from %s for %.3g s: ranking servers '
                              'from its own probes', self.robot_id, self.manager_node or
                              'the manager', self.selection.manager_timeout)
            else:
                rospy.loginfo('robot %d: following the manager again', self.robot_id)

    def summary(self):
        target = self.selection.heading()     # (not target(): a decision, with no kind)
        return 'robot %d: %s; server %s%s, %d switches' % (
            self.robot_id, '; '.join(s.summary() for s in self.streams),
            {NO_SERVER: 'none', LOCAL: 'local'}.get(target, target),
            ' (own decision)' if self._local_decision else '',
            sum(s.flow.switches for s in self.streams))

    def on_shutdown(self):
        for timer in self.timers:
            timer.shutdown()
        for part in self.streams + [self.prober] + [self.view] * (self.view is not None):
            part.shutdown()
        rospy.loginfo(self.summary())


def main():
    run('robot', RobotNode)
