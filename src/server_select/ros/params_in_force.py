"""A node's private parameters on the parameter server as they are in force.

Every default a node reads is written back, so that ``rosparam get /robot1/probe_rate``
shows the value the node uses; what it wrote is taken back when it ends, or, after a crash,
by the next copy of the node at its start (the record of what was written stays beside
them, ``~defaults_written``), so that a later launch with another profile does not take
an earlier run's defaults for settings. A private parameter the node does not know (a
typo in a launch file or a settings YAML) is named, with the nearest known name.
"""

import os

import rospy

from server_select.core.config.params import nearest

RECORD = 'defaults_written'     # {'pid': pid, 'values': {name: value}} of the copy running
_WRITTEN = {}                   # name -> the default this node wrote back
_NAMESPACES = set()             # nested settings a part of the node reads (a plug-in's)


def write_default(name, value):
    """``~name`` was unset and the node uses ``value``: put it on the parameter server."""
    if value is None or name in _WRITTEN:
        return
    _WRITTEN[name] = value
    rospy.set_param('~' + name, value)


def not_in_force(names):
    """The defaults of ``names`` were read but are not in force in this node's profile (a
    fleet robot does not probe at ``~probe_rate``): off the parameter server again, so that
    ``rosparam get`` shows only what the node uses."""
    for name in names:
        if _WRITTEN.pop(name, None) is not None:
            _delete(name)


def changed_live(name, value):
    """``~name`` was tuned to ``value`` while the node runs (dynamic_reconfigure wrote it): a
    default this node wrote is still taken back at its end, as tuned."""
    if name not in _WRITTEN:
        return      # set by the launch: stays as tuned, as dynamic_reconfigure leaves it
    _WRITTEN[name] = value
    if rospy.has_param('~' + RECORD):
        rospy.set_param('~' + RECORD, {'pid': os.getpid(), 'values': dict(_WRITTEN)})


def set_here(name):
    """Whether ``~name`` was set for this node (by a launch file, rosrun or rosparam), not
    written back as a default by it."""
    return name not in _WRITTEN and rospy.has_param('~' + name)


def reads_namespace(name):
    """A part of the node reads the settings under ``~name/`` (a plug-in's): known."""
    _NAMESPACES.add(name)


def take_back_leftovers():
    """At start: a copy of this node that ended without cleaning up (SIGKILL) left its
    defaults; take back those still as it wrote them."""
    left = rospy.get_param('~' + RECORD, None)
    if not isinstance(left, dict) or left.get('pid') == os.getpid():
        return
    _take_back(left.get('values') or {})
    _delete(RECORD)


def record():
    """After start: say what was written (for the next copy, should this one crash), and
    take it back at shutdown."""
    rospy.set_param('~' + RECORD, {'pid': os.getpid(), 'values': dict(_WRITTEN)})
    rospy.on_shutdown(take_back)


def take_back():
    """At shutdown: the defaults this node wrote, and the record, unless a newer copy of
    the node (the same name) has written its own meanwhile."""
    try:
        mine = rospy.get_param('~' + RECORD, {}).get('pid') == os.getpid()
        if mine:
            _take_back(_WRITTEN)
            _delete(RECORD)
    except Exception:       # the master is gone: nothing is left to take back
        pass


def _take_back(values):
    for name, value in sorted(values.items()):
        if rospy.get_param('~' + name, None) == value:
            _delete(name)


def _delete(name):
    """``~name`` off the parameter server; gone already is as good (another copy of the
    node, starting or ending, may take back the same at the same time)."""
    try:
        rospy.delete_param('~' + name)
    except KeyError:
        pass


def unknown(known):
    """``[(name, nearest known name or None)]``: the node's private parameters that are
    neither in ``known`` nor under a namespace a part of it reads."""
    prefix = rospy.get_name().rstrip('/') + '/'
    valid = set(known) | _NAMESPACES | {RECORD}
    found = sorted(set(n[len(prefix):].split('/')[0] for n in rospy.get_param_names()
                       if n.startswith(prefix)))
    return [(name, nearest(name, valid)) for name in found if name not in valid]


def warn_unknown(known):
    """One line per unknown private parameter, naming it and the nearest valid name."""
    for name, near in unknown(known):
        rospy.logwarn('%s: unknown parameter ~%s (set, but this node reads no such '
                      'parameter)%s', rospy.get_name(), name,
                      '; did you mean ~%s?' % near if near else '')
