"""How every node of the package runs: parameters checked, the key's state said, the node
built and started, a restarted roscore followed, spin until shutdown. Above :mod:`node`
and :mod:`seal` (which reads its parameters through :mod:`node`)."""

import sys

import rosgraph
import rospy

from server_select.core.config import names
from server_select.core.util import interrupts
from server_select.core.config.params import ParamError
from server_select.core.settings import PARAMS
from server_select.ros import (bounded_read, diagnostics, given_up, handshake, key_reload,
                               launch_args, launch_run, params_in_force, seal, xmlrpc_bound)
from server_select.ros.master_watch import MasterWatch
from server_select.ros.node import _LIVE, end_parent_launch, fleet, param, quiet_logging


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

    A ParamError becomes one ``logfatal`` line and exit status 2, and ends the roslaunch
    that started the node, so that a launch file with a bad ``<arg>`` fails loudly instead
    of running half-configured. Every node
    registers again with a restarted roscore (:class:`MasterWatch`): a node whose class
    says ``MASTER_WATCHER`` (the manager) checks every ``~master_watch`` s and tells the
    others on ``master_pid``, which check every ``~master_check`` s by themselves.
    """
    if {'-h', '--help'} & set(rospy.myargv(sys.argv if argv is None else argv)[1:]):
        from server_select import paramdoc      # (finds the package's launch files: slow)
        print(paramdoc.usage(node_name, node_class.__doc__ or ''))
        sys.exit(0)
    bounded_read.install()      # every connection header this node reads is bounded,
    handshake.install()         # and an inbound one read off the accept thread, in time
    xmlrpc_bound.install()      # XML-RPC connections: a bounded number, each in time
    given_up.install()          # a subscriber connection rospy gives up on is closed
    # rospy's signal handler would deadlock on a master call of the starting node
    with interrupts.deferred():
        rospy.init_node(node_name, argv=argv, disable_signals=True)
        watch = None if interrupts.held() else _start(node_class)
    if interrupts.held():           # Ctrl-C while it was starting: end as Ctrl-C ends it
        rospy.signal_shutdown('signal %s while starting' % interrupts.held()[0])
        return
    interrupts.on_signal(lambda signum: rospy.signal_shutdown('signal-%d' % signum))
    watch.start()
    rospy.spin()


def _start(node_class):
    """The node built and started; its MasterWatch (not started yet). A ParamError ends
    the node (and its launch)."""
    quiet_logging()
    params_in_force.take_back_leftovers()
    try:
        # a key that cannot be used, or none with ~require_key, ends the node here
        seal.announce(rospy.get_name(), getattr(node_class, 'SEAL_ROLE', None))
        if seal.enabled():
            key_reload.serve()       # keys rotated without a restart
        node = node_class()
        watcher = getattr(node_class, 'MASTER_WATCHER', False)
        watch = MasterWatch(param('master_watch' if watcher else 'master_check'),
                            on_change=_follow_again, watcher=watcher,
                            topic=fleet(names.MASTER_PID_TOPIC))
    except ParamError as error:
        rospy.logfatal('invalid parameter: %s', error)
        launch_run.record_fatal(rospy.get_name(), error)    # for `rosrun ... launch`
        if end_parent_launch():     # no launch runs on half started, without this node
            rospy.logfatal('%s: the launch ends, this node\'s parameter being invalid',
                           rospy.get_name())
        rospy.signal_shutdown('invalid parameter')
        sys.exit(2)
    start = getattr(node, 'start', None)
    if start is not None:
        start()
    diagnostics.start_for(node, getattr(node_class, 'DIAGNOSTICS', None))
    params_in_force.warn_unknown(set(PARAMS) | {'diagnostic_period'})
    launch_args.warn_undeclared(rospy.get_name(), rospy.logwarn)
    params_in_force.record()
    return watch
