"""Wiring shared by the nodes: parameters read through the table, and the main() skeleton."""

import logging
import os
import signal

import rosgraph
import rosgraph.names
import rospy

from server_select.core.config.params import ParamError
from server_select.core.util.procs import wait_until
from server_select.core.settings import PARAMS, REQUIRED, default as profile_default
from server_select.ros import launch_args, params_in_force

_UNSET = object()
_FLEET_NS = None
_PROFILE = None
_LIVE = set()           # private parameters followed through the master's updates
ROSOUT_TOPICS = '/rosout_disable_topics_generation'


def param(name, default=None, parse=None):
    """The private parameter ``~name``, parsed, with its default from the table (in the
    node's ``~profile``).

    ``default`` and ``parse`` override the table's (for a default that depends on another
    parameter, e.g. ``~seed`` defaults to ``~robot_id``). A missing required parameter or
    a value the parser refuses raises :class:`ParamError` naming ``~name``. A default
    used is written back to the parameter server (:mod:`params_in_force`).
    """
    spec = PARAMS[name]
    default = profile_default(name, profile()) if default is None else default
    private = '~' + name
    if default is REQUIRED and not rospy.has_param(private):
        raise ParamError('%s: required parameter is not set (resolved: %s)'
                         % (private, rospy.resolve_name(private)))
    value = rospy.get_param(private, _UNSET)
    if value is _UNSET:
        value = default
        params_in_force.write_default(name, value)
    if value is None:
        return None
    return (parse or spec.parse)(private, value)


def live_param(name):
    """``~name`` as :func:`param` reads it, kept up to date by the master instead of asked
    for: the first call subscribes to it (setting it to its default when unset, so that
    there is a value to follow), later calls read rospy's cache, which the master updates
    on ``rosparam set`` (no master call in steady state)."""
    private = '~' + name
    if private not in _LIVE:
        if not rospy.has_param(private):
            rospy.set_param(private, profile_default(name, profile()))
        _LIVE.add(private)
    return PARAMS[name].parse(private, rospy.get_param_cached(private))


class AbandonedConnections(logging.Filter):
    """rospy warns of every inbound connection closed before its first byte: a client
    that gave up connecting (a probe past its deadline while the node was starting) or
    one that only looked. No message was lost and there is nothing to do about it, so it
    is logged at debug level; a connection that sent a bad header still warns."""
    SIGN = '0 bytes were received'

    def filter(self, record):
        message = record.getMessage()
        if record.levelno == logging.WARNING and message.startswith(
                'Inbound TCP/IP connection failed') and self.SIGN in message:
            rospy.logdebug(message)
            return False
        return True


def quiet_logging():
    """rospy's log handler asks for ``/rosout_disable_topics_generation`` at every log line
    through its parameter cache, which keeps nothing while the parameter is unset: each
    line would be a ``subscribeParam`` call to the master. Set it (to its default, False)
    if unset, so that the cache holds it after the first line. rospy's warning of an
    abandoned connection goes to debug (:class:`AbandonedConnections`)."""
    if not rospy.has_param(ROSOUT_TOPICS):
        rospy.set_param(ROSOUT_TOPICS, False)
    logging.getLogger('rosout').addFilter(AbandonedConnections())


def profile():
    """The node's ``~profile`` (``paper`` unless set)."""
    global _PROFILE
    if _PROFILE is None:
        value = rospy.get_param('~profile', _UNSET)
        if value is _UNSET:
            value = 'paper'
            params_in_force.write_default('profile', value)
        _PROFILE = PARAMS['profile'].parse('~profile', value)
    return _PROFILE


def fleet(name):
    """``name`` resolved in the fleet's namespace (``~fleet_ns``, default ``/``), where every
    fleet-level topic and service lives, wherever the node itself is (a robot in
    ``robot1/`` finds the servers at the root with no remaps)."""
    return rosgraph.names.ns_join(_fleet_ns(), name) if not name.startswith('/') else name


def _fleet_ns():
    global _FLEET_NS
    if _FLEET_NS is None:
        _FLEET_NS = rospy.resolve_name(param('fleet_ns') or '/')
    return _FLEET_NS


def end_parent_launch():
    """Ask the roslaunch that started this node to shut down, as Ctrl-C would (a clean end,
    without the "REQUIRED process has died" of a required node that exits by itself). False
    when the parent is not roslaunch."""
    if launch_args.parent_roslaunch_argv() is None:
        return False
    os.kill(os.getppid(), signal.SIGINT)
    return True


def flush(publisher, timeout=1.0):
    """Wait, at most ``timeout`` s, until every message ``publisher`` queued has gone to its
    subscribers' connections (rospy writes them from a thread per connection, and a node
    that ends right after publishing loses what is still queued; rospy has no flush, so
    this reads its connections' queues). True once flushed."""
    return wait_until(lambda: not any(getattr(c, '_queue', None)
                                      for c in list(publisher.impl.connections)),
                      timeout, period=0.01)


def unregister(endpoint):
    """``endpoint.unregister()`` (a rospy Publisher or Subscriber), then, when that closed
    its topic (no other handle in this node shares it), the topic's poller as well. rospy
    leaves that epoll descriptor to the garbage collector, and a closed topic sits in a
    reference cycle that only a full collection frees: a node that lives for hours and
    makes topics anew (a stalled connection renewed, a robot come and gone) held one more
    descriptor for each: a robot one or two per link outage of one of its servers."""
    impl = endpoint.impl
    endpoint.unregister()
    if impl is not None and impl.closed:
        poller = getattr(getattr(impl, 'connection_poll', None), 'poller', None)
        if hasattr(poller, 'close'):
            poller.close()
