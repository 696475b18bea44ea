"""A robot's selection parts built from its parameters (no rospy): what the robot node
and the simulator build alike."""

import time

from server_select.core.robot.selection import Selection
from server_select.core.robot.health import ServerHealth
from server_select.core.ranking.policy import from_params


def robot_selection(robot_id, servers, mode, fixed, get, clock=time.monotonic, rng=None,
                    rule_args=None):
    """``(Selection, ServerHealth, Policy)`` of a robot from its parameters (``get(name)``
    reads one; ``fixed``: the server of ``fixed`` mode; ``rule_args``: the per-task rule's
    own, the league's ablations): what the robot node and the simulator build alike."""
    eject_time, eject_max = get('eject_time'), get('eject_max')
    if eject_time > eject_max:
        raise ValueError('~eject_time %g is longer than ~eject_max %g' % (eject_time, eject_max))
    health = ServerHealth(servers, eject_time, eject_max, clock=clock)
    policy, statistic = from_params(get)
    selection = Selection(robot_id, servers, mode, fixed, health, get('window'), policy,
                          get('manager_timeout'), clock=clock, statistic=statistic,
                          passive=get('passive') and mode == 'select',
                          task_memory=get('task_memory'), keep=get('window_samples'),
                          horizon=get('window_max'), fail_fast=get('fail_fast'), rng=rng,
                          rule_args=rule_args)
    return selection, health, policy
