"""Which server a robot's next task goes to (no rospy).

``select`` follows the manager's flags, ``fixed`` always names one server (the paper's
baseline), ``local`` keeps the work in the robot.
"""

import threading

from server_select.core.task_flow import LOCAL, NO_SERVER

MODES = ('select', 'fixed', 'local')


class Selection(object):
    """The robot's current target and the switches it made.

    Thread-safe: the flag subscriber writes, the task timers read.
    """

    def __init__(self, robot_id, mode, fixed_server=None):
        if mode not in MODES:
            raise ValueError('unknown mode %r' % (mode,))
        self.robot_id = robot_id
        self.mode = mode
        self.fixed_server = fixed_server
        self._lock = threading.Lock()
        self._selected = NO_SERVER
        self._seen = False
        self.switches = 0

    def on_flag(self, robot_id, server_id):
        """A flag arrived; returns True when it changed this robot's selection."""
        if robot_id != self.robot_id:
            return False
        with self._lock:
            self._seen = True
            if server_id == self._selected:
                return False
            if self._selected != NO_SERVER:
                self.switches += 1
            self._selected = server_id
            return True

    def target(self):
        """The server a task sent now goes to: a server id, NO_SERVER or LOCAL."""
        if self.mode == 'local':
            return LOCAL
        if self.mode == 'fixed':
            return self.fixed_server
        with self._lock:
            return self._selected

    def ready(self, answered):
        """Whether tasks may start: the target is known to be up. ``answered`` is the set of
        servers that have answered a probe (what fixed mode waits for)."""
        if self.mode == 'local':
            return True
        if self.mode == 'fixed':
            return self.fixed_server in answered
        with self._lock:
            return self._seen and self._selected != NO_SERVER
