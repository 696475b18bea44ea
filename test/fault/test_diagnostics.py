"""The fleet's health on /diagnostics, as rosdiagnostic and rqt_robot_monitor read it: every
node OK in a healthy fleet profile run; a server killed (SIGKILL) shows as an error, or
stale, in the manager's status of it within 3 s, and its robots name it."""

import signal
import sys
import threading
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus

from server_select.core.util.procs import wait_until

from support.fleet import Fleet
from support.output import output_until
from test_faults import show, warm_up

LEVELS = {DiagnosticStatus.OK: 'OK', DiagnosticStatus.WARN: 'WARN',
          DiagnosticStatus.ERROR: 'ERROR', DiagnosticStatus.STALE: 'STALE'}


class Statuses(object):
    """The newest status of each name on /diagnostics, with when it changed level."""

    def __init__(self):
        self.lock = threading.Lock()
        self.now, self.changes = {}, []
        self.sub = rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_array,
                                    queue_size=100)

    def on_array(self, array):
        with self.lock:
            for status in array.status:
                before = self.now.get(status.name)
                if before is None or before.level != status.level:
                    self.changes.append((time.monotonic(), status.name, status.level,
                                         status.message))
                self.now[status.name] = status

    def level(self, name):
        with self.lock:
            status = self.now.get(name)
        return None if status is None else status.level

    def first(self, name, levels, since):
        with self.lock:
            return next((t for t, n, level, _ in self.changes
                         if n == name and level in levels and t >= since), None)


def test_a_killed_server_is_an_error_on_diagnostics_within_3_s(ros):
    statuses = Statuses()
    try:
        with Fleet(ros['log'], profile='fleet', task_rate=5) as fleet:
            warm_up(ros['rec'])
            names = ['manager: server %d' % s for s in (1, 2, 3)] + \
                ['robot%d: selection' % r for r in (1, 2)] + \
                ['server%d: load' % s for s in (1, 2, 3)]
            healthy = wait_until(lambda: all(statuses.level(n) == DiagnosticStatus.OK
                                             for n in names), 15.0)
            before = dict((n, '%s: %s' % (LEVELS.get(statuses.level(n)), statuses.now[n].message)
                           if n in statuses.now else None) for n in names)
            t_kill = time.monotonic()
            fleet.signal('/server2', signal.SIGKILL)
            seen = wait_until(lambda: statuses.first(
                'manager: server 2', (DiagnosticStatus.ERROR, DiagnosticStatus.STALE),
                t_kill), 10.0, period=0.05)
            after = statuses.first('manager: server 2', (DiagnosticStatus.ERROR,
                                                         DiagnosticStatus.STALE), t_kill)
            robots_say = [statuses.now['robot%d: selection' % r].message for r in (1, 2)]
            shown = rosdiagnostic('--filter', '^manager: server 2$', '-l', '2')
    finally:
        statuses.sub.unregister()
    took = after - t_kill if after else None
    show('/diagnostics, a fleet profile run, server 2 killed (SIGKILL):', [{
        'every node OK before': healthy, 'levels before': before,
        "manager's status of server 2 ERROR/STALE after s": '%.2f' % took if took else 'never',
        'the robots say': robots_say, 'rosdiagnostic': shown.strip()}])
    assert healthy, before
    assert seen and took <= 3.0, took
    assert '[ ERROR ] manager: server 2 - not answering robots 1, 2' in shown, shown


def rosdiagnostic(*args, until='[ ERROR ]', timeout=10.0):
    """What Debian's rosdiagnostic prints of /diagnostics (``--follow``) until a line holds
    ``until``, at most ``timeout`` s (Debian ships its module without a script: its main)."""
    return output_until(
        [sys.executable, '-c', 'import sys, rosdiagnostic; rosdiagnostic.rosdiagnosticmain('
         'sys.argv)', '--topic', '/diagnostics', '--nocolor', '--follow'] + list(args),
        until, timeout)
