"""A robot's parts, built from its parameters (the node, :mod:`server_select.nodes.robot`,
wires them): its selection and health table, its prober, a task stream per kind, the
servers that joined and wait for their task topics."""

import functools
import threading

import rospy

from server_select.core.config.params import ParamError, parse_fixed_server
from server_select.core.flow import attempts
from server_select.core.flow.task_flow import HEDGE_QUANTILE
from server_select.core.selection import probing
from server_select.core.selection import robot_parts
from server_select.core.selection.effect import ineffective, refusal
from server_select.ros import params_in_force, seal
from server_select.ros.load import load_of
from server_select.ros.probe_seal import ProbeAddresses
from server_select.ros.node import param
from server_select.ros.prober import Prober
from server_select.ros.routing import ROUTES
from server_select.ros.task_stream import TaskStream


def robot_selection(robot_id, servers, mode):
    """``(Selection, ServerHealth, Policy)`` of a robot from its parameters (a parameter
    set that is not for setting with the others is refused:
    :mod:`~server_select.core.selection.effect`)."""
    refused = refusal(ineffective(param, params_in_force.set_here))
    if refused:
        raise ParamError(refused)
    fixed = param('fixed_server', default=servers[0] if servers else None,
                  parse=lambda name, value: parse_fixed_server(name, value, servers, mode))
    try:
        return robot_parts.robot_selection(robot_id, servers, mode, fixed, param)
    except ValueError as error:
        raise ParamError(str(error))


def robot_prober(robot, servers):
    """``(ProbeAddresses or None, Prober)`` of ``robot`` (a RobotNode) from its parameters."""
    plan = probing.from_params(param)
    # with a fleet key: servers probed where their sealed announcements say
    addresses = ProbeAddresses('robot %d' % robot.robot_id) if seal.enabled() else None
    return addresses, Prober(robot.robot_id, servers, plan, param('probe_timeout'),
                             on_sample=robot.on_sample, stream=param('sample_stream'),
                             load_of=(lambda server, response, rtt: robot.load.on_answer(
                                 server, load_of(response), rtt)) if robot.load else None,
                             announce=robot.load.announcement if robot.load else None,
                             contenders=robot.selection if plan.adaptive else None,
                             node_of=robot.server_node, addresses=addresses)


def task_stream(robot, kind, rate, mode):
    """The TaskStream of ``robot`` (a RobotNode) for ``kind`` at ``rate``."""
    return TaskStream(robot.robot_id, kind, rate, param('tasks'), robot.ready, dict(
        timeout=param('task_timeout'),
        candidates=functools.partial(robot.selection.candidates, kind.kind),
        attempts=robot.selection.balancer, on_failure=robot.on_failure,
        on_success=robot.health.task_ok, ids=robot._task_ids,
        on_busy=functools.partial(robot.on_busy, kind.kind),
        hedge=HEDGE_QUANTILE if param('hedge') else None, budget=robot.budget,
        copies=robot.selection.balancer.copies if robot.selection.balancer else 1,
        max_in_flight=param('max_in_flight'),
        newest_wins=kind.newest_wins,
        deadlines=attempts.from_params(param, kind.kind, rate, kind.newest_wins, robot.load),
        on_answer=functools.partial(robot.passive.on_answer, kind.kind)
        if robot.passive else None), local=mode == 'local',
        expected_publisher=robot.server_node, route=ROUTES[param('routing')], load=robot.load,
        listeners=[rospy.resolve_name(n) for n in param('report_listeners')])


class Joining(object):
    """Servers that joined the fleet, probed at once but task candidates (``admit``) only
    once every task stream's topic reaches them: a task published before the server's
    connection is up reaches nobody. (Seen: a joined server selected 0.1 s after its first
    probe answer, its first task lost, the server ejected for 1 s.)"""

    def __init__(self, streams, admit):
        self.streams, self.admit = streams, admit
        self.waiting = set()
        self._lock = threading.Lock()   # membership's thread adds, the robot's timer checks

    def add(self, server):
        with self._lock:
            self.waiting.add(server)
        self.check()

    def discard(self, server):
        with self._lock:
            self.waiting.discard(server)

    def check(self):
        """Admit the servers whose task topics are connected now (the robot's timer)."""
        with self._lock:
            for server in sorted(self.waiting):
                if all(stream.wired_to(server) for stream in self.streams):
                    self.waiting.discard(server)
                    self.admit(server)
