"""The robot node's side of its :class:`~server_select.core.robot.robot.Robot`: the
parameters checked before it is built, and :class:`RobotWire`, its transport and events on
rospy (probes by the :class:`~server_select.ros.prober.Prober`, tasks on each stream's
topics, every event a log line or a message)."""

import rospy

from server_select.core.config.params import ParamError, parse_fixed_server
from server_select.core.robot.world import Events, Transport
from server_select.core.robot.refusals import ineffective, not_for_setting, refusal
from server_select.ros import params_in_force, seal
from server_select.ros.load import load_of
from server_select.ros.node import param
from server_select.ros.passive import TaskSamples
from server_select.ros.probe_seal import ProbeAddresses
from server_select.ros.prober import Prober
from server_select.ros.routing import ROUTES
from server_select.ros.task_stream import TaskStream


def not_in_force():
    """The parameters a robot read but does not use in its configuration: off the parameter
    server (as its defaults they were written back)."""
    params_in_force.not_in_force([name for name, _ in not_for_setting(param)] +
                                 (['fixed_server'] if param('mode') != 'fixed' else []))


def fixed_server(servers, mode):
    """The server of ``fixed`` mode from the parameters (a parameter set that is not for
    setting with the others is refused: :mod:`~server_select.core.robot.refusals`)."""
    refused = refusal(ineffective(param, params_in_force.set_here))
    if refused:
        raise ParamError(refused)
    return param('fixed_server', default=servers[0] if servers else None,
                 parse=lambda name, value: parse_fixed_server(name, value, servers, mode))


class RobotWire(Transport, Events):
    """Robot ``robot_id``'s transport and events on rospy, for a node whose
    ``server_node(server, refresh)`` names the node a server's answers must come from."""

    def __init__(self, robot_id, server_node, load_aware):
        self.robot_id, self.server_node = robot_id, server_node
        # with a fleet key: servers probed where their sealed announcements say
        self.addresses = ProbeAddresses('robot %d' % robot_id) if seal.enabled() else None
        self.prober = Prober(robot_id, param('probe_timeout'), param('sample_stream'),
                             load_of=load_of if load_aware else None, node_of=server_node,
                             addresses=self.addresses)
        self.streams = {}       # kind -> its TaskStream
        self.passive = None
        self.on_move = None     # on_move(): the rule moved the robot's tasks (its views)

    def attach(self, robot):
        """Wire ``robot``'s streams to their topics."""
        local = robot.mode == 'local'
        listeners = [rospy.resolve_name(n) for n in param('report_listeners')]
        for core in robot.streams:
            self.streams[core.kind.kind] = TaskStream(
                self.robot_id, core, local=local, expected_publisher=self.server_node,
                route=ROUTES[param('routing')], listeners=listeners)
        self.passive = TaskSamples(self.robot_id) if robot.baseline is not None else None

    # -- the transport --------------------------------------------------------------------
    def connect(self, server):
        self.prober.add(server)
        for stream in self.streams.values():
            stream.add_server(server)

    def disconnect(self, server):
        self.prober.remove(server)
        for stream in self.streams.values():
            stream.remove_server(server)

    def probe(self, server, seq, kinds, rates):
        return self.prober.probe(server, seq, kinds, rates)

    def send_task(self, kind, request, server, budget):
        self.streams[kind].publish(request, server, budget)

    def heard(self, server, rtt):
        for stream in self.streams.values():
            stream.heard(server)

    def wired(self, server):
        return all(stream.wired_to(server) for stream in self.streams.values())

    def unready(self, kind):
        return self.streams[kind].unready()

    # -- the events -----------------------------------------------------------------------
    def round(self, number, servers):
        self.prober.round(number, servers)

    def sample(self, server, seq, rtt, error, wait, round_number):
        self.prober.sample(server, seq, rtt, error, wait, round_number)

    def bad_sample(self, server, error):
        rospy.logwarn_throttle(5.0, 'robot %d: own probe of server %d: %s'
                               % (self.robot_id, server, error))

    def task_sample(self, server, seconds):
        self.passive.publish(server, seconds)

    def ejected(self, server, ejection, why):
        if ejection.seconds:
            rospy.logwarn('robot %d: server %d ejected for %.3g s: %s', self.robot_id,
                          server, ejection.seconds, why)
        else:
            rospy.logwarn('robot %d: server %d has not answered yet (%s): a candidate once '
                          'it answers', self.robot_id, server, why)

    def moved(self, server, why, kind):
        rospy.loginfo('robot %d: %s tasks go to server %d now (%s)', self.robot_id, kind,
                      server, why)
        if self.on_move is not None:
            self.on_move()

    def waiting(self, kind, what):
        rospy.loginfo_throttle(5.0, 'robot %d: %s tasks wait for %s'
                               % (self.robot_id, kind, what))

    def no_input(self, kind, seconds):
        rospy.loginfo_throttle(5.0, 'robot %d: no input for %s tasks from %s for %.1f s' % (
            self.robot_id, kind, self.streams[kind].kind.input, seconds))

    def started(self, kind):
        rospy.loginfo('robot %d: sending %s tasks', self.robot_id, kind)

    def report(self, outcome):
        self.streams[outcome.kind].report(outcome)
