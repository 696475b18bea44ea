"""Wiring shared by the node modules: parameter access and the main() skeleton."""

import sys

import rospy

from server_select.params import ParamError

REQUIRED = object()


def get_param(name, default=REQUIRED):
    """``rospy.get_param`` that turns a missing required parameter into a ParamError."""
    if default is REQUIRED:
        if not rospy.has_param(name):
            raise ParamError('%s: required parameter is not set (resolved: %s)'
                             % (name, rospy.resolve_name(name)))
        return rospy.get_param(name)
    return rospy.get_param(name, default)


def run(node_name, node_class, argv=None):
    """Initialise the node, build ``node_class()`` and spin until shutdown.

    A ParamError becomes one ``logfatal`` line and exit status 2, so that a launch file
    with a bad ``<arg>`` fails loudly instead of running half-configured.
    """
    rospy.init_node(node_name, argv=argv)
    try:
        node_class()
    except ParamError as error:
        rospy.logfatal('invalid parameter: %s', error)
        rospy.signal_shutdown('invalid parameter')
        sys.exit(2)
    rospy.spin()
