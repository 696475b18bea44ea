"""``rosrun server_select top`` in a real terminal (tmux: a pane of 120 x 40, keys sent,
the screen captured) against a running fleet: it shows every server and robot, a server
killed with SIGKILL as gone, the robots' switch away from it, and quits on ``q``."""

import os
import shlex
import shutil
import signal
import subprocess
import sys
import time

import pytest

from server_select.core.util.procs import wait_until

from support.fleet import Fleet
from test_faults import STABLE, show, warm_up

TOP = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'scripts', 'top')


class Pane(object):
    """A tmux server of the test's own with one 120 x 40 pane running ``command``."""

    def __init__(self, command):
        self.socket = 'server_select_top_%d' % os.getpid()
        env = ' '.join('%s=%s' % (k, shlex.quote(os.environ[k])) for k in (
            'ROS_MASTER_URI', 'ROS_PACKAGE_PATH', 'PYTHONPATH', 'PATH', 'ROS_HOME')
            if k in os.environ)
        self.tmux('new-session', '-d', '-s', 'top', '-x', '120', '-y', '40',
                  'env %s %s' % (env, command))

    def tmux(self, *args):
        return subprocess.run(['tmux', '-L', self.socket] + list(args), check=True,
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                              universal_newlines=True, timeout=10).stdout

    def screen(self):
        try:
            return self.tmux('capture-pane', '-p', '-t', 'top').splitlines()
        except subprocess.CalledProcessError:     # the pane has closed
            return None

    def row(self, head, key):
        """The cells of ``key``'s row under the header starting with ``head``, or None."""
        lines = self.screen() or []
        start = next((i for i, line in enumerate(lines) if line.startswith(head)), None)
        for line in lines[start + 1:] if start is not None else []:
            if not line.strip():
                return None
            if line.split()[0] == str(key):
                return line.split()
        return None

    def close(self):
        subprocess.run(['tmux', '-L', self.socket, 'kill-server'], stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)


@pytest.mark.skipif(shutil.which('tmux') is None, reason='tmux is not installed')
def test_top_shows_the_fleet_a_killed_server_and_the_switch(ros):
    rec = ros['rec']
    rec.clear()
    with Fleet(ros['log'], **STABLE) as fleet:
        warm_up(rec)
        pane = Pane('%s %s --servers 1,2,3' % (sys.executable, TOP))
        try:
            assert wait_until(lambda: pane.row('SERVER', 3) is not None and all(
                (pane.row('SERVER', s) or ['', ''])[1] == 'up' for s in (1, 2, 3)) and
                all(pane.row('ROBOT', r) for r in (1, 2)), 20.0), pane.screen()
            victim = int(pane.row('ROBOT', 1)[1])
            t_kill = time.monotonic()
            fleet.signal('/server%d' % victim, signal.SIGKILL)
            assert wait_until(lambda: (pane.row('SERVER', victim) or ['', ''])[1] == 'GONE',
                              10.0, period=0.05), pane.screen()
            gone = time.monotonic() - t_kill
            # robot 1's first task elsewhere, then how long the screen takes to say so
            assert wait_until(lambda: any(r.msg.server_id != victim for r in
                                          rec.of(rec.reports, 1, t_kill)), 15.0)
            t_moved = next(r.time for r in rec.of(rec.reports, 1, t_kill)
                           if r.msg.server_id != victim)
            assert wait_until(lambda: (pane.row('ROBOT', 1) or ['', ''])[1] != str(victim),
                              10.0, period=0.05), pane.screen()
            shown = time.monotonic() - t_moved
            screen = pane.screen()
            pane.tmux('send-keys', '-t', 'top', 'q')
            assert wait_until(lambda: pane.screen() is None, 10.0), 'top did not quit on q'
        finally:
            pane.close()
    show('top in tmux, server %d killed:' % victim, [{
        'shown gone after s': '%.2f' % gone, 'switch shown after s': '%.2f' % shown}])
    print('\n'.join(screen))
    assert gone <= 2.0, gone
    assert shown <= 2.0, shown
    assert any('server %d gone' % victim in line for line in screen), screen
