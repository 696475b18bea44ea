"""A robot's settings tuned while it runs, with dynamic_reconfigure: ``dynparam set /robot1
window 3.0`` or ``rqt_reconfigure``. Each change is checked by the parameter's own parser,
put in force (:mod:`server_select.core.robot.tuning`), logged with its old and new value
and written back to ``~name``; a value that cannot be taken is refused with the reason and
the setting keeps its value. The settings are described at run time from the node's own
table (:mod:`server_select.core.settings`): no ``.cfg`` file to keep in step.

With a fleet key the service is not offered: its calls are not signed, and a keyed fleet
takes its settings from its launch files only.
"""

import types

import rospy
from dynamic_reconfigure.server import Server

from server_select.core.config.params import ParamError
from server_select.core.robot.tuning import LIVE, Tuning
from server_select.core.settings import PARAMS
from server_select.ros import bounded_read, params_in_force, seal

# dynamic_reconfigure's type and bounds of each Python type: no bounds of its own for a
# number (it would clamp a value out of them silently; the parameter's parser refuses it)
TYPES = {float: ('double', -float('inf'), float('inf')), bool: ('bool', False, True)}
MAX_REQUEST = 64 << 10      # a Reconfigure request of every live setting is about 1 KB


def config_type(names, values):
    """What dynamic_reconfigure's generated ``<name>Config`` module holds, for ``names``
    with their ``values`` now as defaults."""
    params = [dict(zip(('type', 'min', 'max'), TYPES[LIVE[name]]), name=name,
                   level=1 << index, default=LIVE[name](values[name]),
                   description=PARAMS[name].doc, edit_method='')
              for index, name in enumerate(names)]
    description = {'name': 'Default', 'type': '', 'state': True, 'cstate': 'true', 'id': 0,
                   'parent': 0, 'parameters': params, 'groups': []}
    by = lambda key: dict((p['name'], p[key]) for p in params)     # noqa: E731
    return types.SimpleNamespace(config_description=description, defaults=by('default'),
                                 min=by('min'), max=by('max'), level=by('level'),
                                 type=by('type'), all_level=(1 << len(params)) - 1)


class LiveTuning(object):
    """The robot node's dynamic_reconfigure server over its robot (``current(name)`` reads
    a setting as the node took it at start); ``after()`` is called after each change (the
    node wakes its streams' pacers)."""

    def __init__(self, who, robot, current, after=None):
        self.who, self.after = who, after
        self.tuning = Tuning(robot, current)
        self.server = None

    def start(self):
        if seal.enabled():
            rospy.loginfo('%s: live tuning (dynamic_reconfigure) is off: its calls are not '
                          'signed, and this fleet has a key', self.who)
            return
        bounded_read.limit(rospy.resolve_name('~set_parameters'), MAX_REQUEST)
        self.server = Server(config_type(self.tuning.names, self.tuning.values), self.on_config)

    def on_config(self, config, _level):
        """dynamic_reconfigure's callback: the settings asked for, all in force, or none
        and the caller told why (``dynparam`` prints it)."""
        try:
            changes = self.tuning.set_all(dict(
                (name, PARAMS[name].parse('~' + name, config[name]))
                for name in self.tuning.names if name in config))
        except (ParamError, ValueError) as error:
            rospy.logwarn('%s: refused a live change: %s' % (self.who, error))
            raise rospy.ServiceException('refused: %s (nothing changed)' % error)
        for name, old, new in changes:
            rospy.loginfo('%s: ~%s %r -> %r (dynamic_reconfigure)', self.who, name, old, new)
            params_in_force.changed_live(name, new)
        if changes and self.after is not None:
            self.after()
        for name in self.tuning.names:
            config[name] = LIVE[name](self.tuning.values[name])
        return config
