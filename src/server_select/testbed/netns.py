"""Testbed hosts in network namespaces joined by the link emulator (no rospy).

A :class:`Testbed` gives every host of a scenario its own network namespace
``<prefix>-<host>`` and address ``<subnet>.<n>``, starts :mod:`server_select.testbed.linkemu`
between them, runs commands inside hosts, and tears everything down on exit, Ctrl-C or
error. Each run has a namespace prefix of its own (by default ``ssb<pid>``): it removes
only what it created, and what a run whose process has died left behind
(:mod:`server_select.testbed.traces`). Needs root, TUN.
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import time

from server_select.core.util.procs import stop_group, stop_groups
from server_select.testbed import busy, cpu
from server_select.testbed.linkemu import EmulatorError
from server_select.testbed.traces import STATE_DIR, cleanup, cleanup_abandoned


def check_privileges():
    """Raise EmulatorError with a clear reason when the testbed cannot run here."""
    if os.geteuid() != 0:
        raise EmulatorError('the testbed needs root (network namespaces, TUN devices): '
                            'run as root, e.g. with sudo')
    if not os.path.exists('/dev/net/tun'):
        raise EmulatorError('the testbed needs TUN support: /dev/net/tun is missing')
    if shutil.which('ip') is None:
        raise EmulatorError('the testbed needs the "ip" command (Debian package iproute2)')


def available():
    """(True, '') when the testbed can run here, else (False, reason)."""
    try:
        check_privileges()
    except EmulatorError as error:
        return False, str(error)
    return True, ''


class Testbed(object):
    """The hosts of one scenario, up between ``__enter__`` and ``__exit__``."""

    def __init__(self, scenario, scenario_path, run_dir, prefix=None, subnet='10.231.0',
                 seed=0):
        prefix = prefix or 'ssb%d' % os.getpid()
        self.scenario = scenario
        self.scenario_path = os.path.abspath(scenario_path)
        self.run_dir = os.path.abspath(run_dir)
        self.prefix = prefix
        self.seed = seed
        self.hosts = {}
        for index, name in enumerate(scenario.hosts, start=1):
            self.hosts[name] = {'netns': '%s-%s' % (prefix, name),
                                'address': '%s.%d' % (subnet, index),
                                'device': '%s%d' % (prefix, index)}
        self.limits = cpu.limits(scenario.hosts.values(), prefix)   # CPU shares
        self.emulator = None
        self.t0 = None
        self.processes = []
        self._old_handlers = {}

    def address(self, host):
        return self.hosts[host]['address']

    def __enter__(self):
        self.up()
        return self

    def __exit__(self, *exc):
        return self.down()

    def up(self):
        check_privileges()
        cleanup(self.prefix)
        cleanup_abandoned()
        os.makedirs(self.run_dir, exist_ok=True)
        self._write_state(None)
        for sig in (signal.SIGTERM, signal.SIGHUP):
            self._old_handlers[sig] = signal.signal(sig, self._on_signal)
        try:
            for host in self.hosts.values():
                netns = host['netns']
                subprocess.run(['ip', 'netns', 'add', netns], check=True)
                subprocess.run(['ip', '-n', netns, 'link', 'set', 'lo', 'up'], check=True)
                subprocess.run(['ip', 'netns', 'exec', netns, 'sysctl', '-q', '-w',
                                'net.ipv6.conf.all.disable_ipv6=1'], check=True)
            for limit in self.limits.values():
                limit.create()
            hosts_file = os.path.join(self.run_dir, 'hosts.json')
            with open(hosts_file, 'w') as stream:
                json.dump(self.hosts, stream, indent=1)
            held = ['--hold'] if self.scenario.time_zero == 'ready' else []
            self.emulator = subprocess.Popen(
                [sys.executable, '-m', 'server_select.testbed.linkemu',
                 '--scenario', self.scenario_path, '--hosts', hosts_file, '--seed', str(self.seed),
                 '--stats', os.path.join(self.run_dir, 'link_stats.json')] + held,
                stdin=subprocess.PIPE, stdout=subprocess.PIPE, universal_newlines=True,
                start_new_session=True)
            self._write_state(self.emulator.pid)
            line = self.emulator.stdout.readline().split()
            if len(line) != 2 or line[0] != 'ready':
                raise EmulatorError('link emulator did not start (exit %s)' % self.emulator.wait())
            self.t0 = None if held else float(line[1])
            self._start_own_work()
        except BaseException:
            self.down()
            raise

    def _start_own_work(self):
        """Each ``busy`` host's own work: a process using that share of its CPU."""
        for host in (h for h in self.scenario.hosts.values() if h.busy):
            self.popen(host.name, busy.command(host), log=os.path.join(
                self.run_dir, '%s_busy.log' % host.name))

    def _write_state(self, emulator_pid):
        """What a later run needs to clean up after this one if its process dies."""
        os.makedirs(STATE_DIR, exist_ok=True)
        with open(os.path.join(STATE_DIR, self.prefix + '.json'), 'w') as stream:
            json.dump({'owner_pid': os.getpid(), 'emulator_pid': emulator_pid,
                       'run_dir': self.run_dir}, stream)

    def _on_signal(self, signum, _frame):
        raise KeyboardInterrupt('signal %d' % signum)

    def start_clock(self):
        """Start the scenario's time now, if it waits for this (its ``time_zero: ready``:
        the runner calls this once its nodes are up); t0, epoch s."""
        if self.t0 is None:
            self.emulator.stdin.write('go\n')
            self.emulator.stdin.flush()
            line = self.emulator.stdout.readline().split()
            if len(line) != 2 or line[0] != 'clock':
                raise EmulatorError('link emulator did not start its clock (exit %s)'
                                    % self.emulator.poll())
            self.t0 = float(line[1])
        return self.t0

    def scenario_time(self):
        """Seconds since time zero; 0 while the scenario's time has not started."""
        return 0.0 if self.t0 is None else time.time() - self.t0

    def sleep_until(self, t):
        """Sleep until scenario time ``t``."""
        while self.scenario_time() < t:
            time.sleep(min(0.2, max(0.0, t - self.scenario_time())))

    def popen(self, host, argv, env=None, log=None, stage=0, **kwargs):
        """Start ``argv`` inside ``host``; it is stopped by :meth:`down`, with the others of
        its ``stage``: the nodes (0) at once, then a recorder (1), then the master (2)."""
        stream = open(log, 'w') if log else subprocess.DEVNULL
        proc = subprocess.Popen(['ip', 'netns', 'exec', self.hosts[host]['netns']] + list(argv),
                                env=env, stdout=stream, stderr=subprocess.STDOUT,
                                start_new_session=True, preexec_fn=self._joiner(host),
                                **kwargs)
        self.processes.append((stage, proc))
        return proc

    def run(self, host, argv, env=None, timeout=60, **kwargs):
        """Run ``argv`` inside ``host`` to completion; return the CompletedProcess."""
        return subprocess.run(['ip', 'netns', 'exec', self.hosts[host]['netns']] + list(argv),
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              universal_newlines=True, timeout=timeout,
                              preexec_fn=self._joiner(host), **kwargs)

    def _joiner(self, host):
        """What a process started in ``host`` runs before its command: SIGINT as by default
        (:meth:`down` stops processes with it, and a testbed started from a background job
        would hand them SIGINT ignored), and joining the host's CPU limit, if it has one
        (its children inherit both)."""
        limit = self.limits.get(host)

        def prepare():
            signal.signal(signal.SIGINT, signal.SIG_DFL)
            if limit is not None:
                limit.join()
        return prepare

    def down(self):
        """Stop all that was started and delete the namespaces (signals wait till done)."""
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            self._old_handlers.setdefault(sig, signal.signal(sig, signal.SIG_IGN))
        for stage in sorted(set(s for s, _ in self.processes)):
            stop_groups([p for s, p in self.processes if s == stage])
        self.processes = []
        if self.emulator is not None:
            stop_group(self.emulator, signal.SIGTERM, 5.0)
            self.emulator = None
        cleanup(self.prefix)
        for sig, handler in self._old_handlers.items():
            signal.signal(sig, handler)
        self._old_handlers = {}
        return False
