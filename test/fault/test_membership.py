"""Fleet membership without the master: servers announce themselves with a lease.

A fleet-profile manager and three servers in a namespace of their own (``fleet_ns``
``/members``), the servers announcing every 0.5 s (a lease of 1.5 s). Real signals: a
server stopped with SIGINT says it leaves; one killed with SIGKILL, or stopped with
SIGSTOP, leaves when its lease ends, and the stopped one is back when continued; a
manager killed and started again lists the running servers in its first list, never an
empty fleet. What ``fleet_servers`` said, and when, is printed.
"""

import os
import signal
import subprocess
import threading
import time

import rospy

from server_select.core.util.procs import stop_groups, wait_until
from server_select.msg import FleetServers
from server_select.ros.graph import publisher_of

from support.fleet import Fleet
from test_faults import show

NS = '/members'
PERIOD = 0.5            # each server's announcement period: a lease of 1.5 s
LEASE = 3 * PERIOD


class Lists(object):
    """The ``fleet_servers`` lists received: (monotonic time, publisher, servers)."""

    def __init__(self):
        self.lock = threading.Lock()
        self.got = []
        self.sub = rospy.Subscriber(NS + '/fleet_servers', FleetServers, self.on_list,
                                    queue_size=100)

    def on_list(self, msg):
        with self.lock:
            self.got.append((time.monotonic(), publisher_of(msg), list(msg.servers)))

    def last(self):
        with self.lock:
            return self.got[-1][2] if self.got else None

    def since(self, start):
        with self.lock:
            return [g for g in self.got if g[0] >= start]

    def when(self, servers, timeout):
        """Wait until the last list is ``servers``; the time it arrived (None: never)."""
        if not wait_until(lambda: self.last() == servers, timeout):
            return None
        with self.lock:
            return self.got[-1][0]


def node(kind, name, *args):
    return subprocess.Popen(
        ['rosrun', 'server_select', kind, '__name:=%s' % name, '_fleet_ns:=%s' % NS,
         '_profile:=fleet'] + list(args),
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)


def manager():
    return node('manager', 'members_manager', '_announce_period:=%g' % PERIOD)


def test_servers_join_and_leave_by_announcement_and_lease(ros):
    lists = Lists()
    procs = [manager()] + [node('server', 'members_server%d' % s, '_server_id:=%d' % s,
                                '_announce_period:=%g' % PERIOD) for s in (1, 2, 3)]
    try:
        all_in = lists.when([1, 2, 3], 60.0)
        assert all_in, lists.got
        pid = dict((s, Fleet.pid('/members_server%d' % s)) for s in (1, 2, 3))
        t_int = time.monotonic()
        os.kill(pid[2], signal.SIGINT)
        left_int = lists.when([1, 3], 10.0)
        t_kill = time.monotonic()
        os.kill(pid[3], signal.SIGKILL)
        left_kill = lists.when([1], 10.0)
        t_stop = time.monotonic()
        os.kill(pid[1], signal.SIGSTOP)
        left_stop = lists.when([], 10.0)
        t_cont = time.monotonic()
        os.kill(pid[1], signal.SIGCONT)
        back = lists.when([1], 10.0)
        t_restart = time.monotonic()
        os.kill(Fleet.pid('/members_manager'), signal.SIGKILL)
        procs.append(manager())
        wait_until(lambda: lists.since(t_restart), 30.0)
        first_new = next(iter(lists.since(t_restart)), None)
        relisted = first_new and first_new[0]
    finally:
        stop_groups(procs, signal.SIGINT, 10.0)
    show('servers announcing every %.1f s (lease %.1f s); fleet_servers after:' % (
        PERIOD, LEASE, ), [{
            'SIGINT server 2 s': '%.2f' % (left_int - t_int) if left_int else 'never',
            'SIGKILL server 3 s': '%.2f' % (left_kill - t_kill) if left_kill else 'never',
            'SIGSTOP server 1 s': '%.2f' % (left_stop - t_stop) if left_stop else 'never',
            'SIGCONT server 1 s': '%.2f' % (back - t_cont) if back else 'never',
            'new manager lists s': '%.2f' % (relisted - t_restart) if relisted else 'never',
            "new manager's first list": first_new and first_new[2]}])
    # a clean stop is news at once; the others wait for the lease (less one period at
    # most: it runs from the last announcement), checked every second
    assert left_int and left_int - t_int < LEASE - PERIOD, lists.got[-3:]
    assert left_kill and LEASE - PERIOD - 0.1 <= left_kill - t_kill <= LEASE + 1.5
    assert left_stop and LEASE - PERIOD - 0.1 <= left_stop - t_stop <= LEASE + 1.5
    assert back and back - t_cont <= PERIOD + 1.0
    assert relisted and first_new == (relisted, '/members_manager', [1]), \
        lists.since(t_restart)
