"""How every node of the package runs: parameters checked, the key's state said, the node
built and started, a restarted roscore followed, spin until shutdown. Above :mod:`node`
and :mod:`seal` (which reads its parameters through :mod:`node`)."""

import sys

import rosgraph
import rospy

from server_select.core.config import names
from server_select.core.config.params import ParamError
from server_select import paramdoc
from server_select.core.settings import PARAMS
from server_select.ros import launch_args, params_in_force, seal
from server_select.ros.master_watch import MasterWatch
from server_select.ros.node import _LIVE, fleet, param, quiet_logging


def _follow_again(what):
    """After a roscore restart (its parameter server starts empty): the followed
    parameters' values back on it, and their subscriptions with it."""
    if what != 'restarted':
        return
    master = rosgraph.Master(rospy.get_name())
    for private in sorted(_LIVE):
        value = rospy.get_param_cached(private)          # this node's cache: no call
        rospy.set_param(private, value)
        master.subscribeParam(rospy.core.get_node_uri(), rospy.resolve_name(private))


def run(node_name, node_class, argv=None):
    """Initialise the node, build ``node_class()``, start it and spin until shutdown.

    A ParamError becomes one ``logfatal`` line and exit status 2, so that a launch file
    with a bad ``<arg>`` fails loudly instead of running half-configured. Every node
    registers again with a restarted roscore (:class:`MasterWatch`): a node whose class
    says ``MASTER_WATCHER`` (the manager) checks every ``~master_watch`` s and tells the
    others on ``master_pid``, which check every ``~master_check`` s by themselves.
    """
    if {'-h', '--help'} & set(rospy.myargv(sys.argv if argv is None else argv)[1:]):
        print(paramdoc.usage(node_name, node_class.__doc__ or ''))
        sys.exit(0)
    rospy.init_node(node_name, argv=argv)
    quiet_logging()
    params_in_force.take_back_leftovers()
    try:
        # a key that cannot be used, or none with ~require_key, ends the node here
        seal.announce(rospy.get_name(), getattr(node_class, 'SEAL_ROLE', None))
        node = node_class()
        watcher = getattr(node_class, 'MASTER_WATCHER', False)
        watch = MasterWatch(param('master_watch' if watcher else 'master_check'),
                            on_change=_follow_again, watcher=watcher,
                            topic=fleet(names.MASTER_PID_TOPIC))
    except ParamError as error:
        rospy.logfatal('invalid parameter: %s', error)
        rospy.signal_shutdown('invalid parameter')
        sys.exit(2)
    start = getattr(node, 'start', None)
    if start is not None:
        start()
    params_in_force.warn_unknown(PARAMS)
    launch_args.warn_undeclared(rospy.get_name(), rospy.logwarn)
    params_in_force.record()
    watch.start()
    rospy.spin()
