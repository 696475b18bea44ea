"""Userspace link emulator: forwards IPv4 packets between TUN devices with per-pair delay
and bandwidth.

The kernel here has no ``netem``. Each testbed host gets one TUN device, moved into the
host's network namespace; this process keeps the device's file descriptor, reads every
packet a host sends, and writes it to the destination host's TUN after the one-way delay
the scenario gives that pair at that moment (plus jitter, loss, or a "down" link).
Packets of one direction of a pair leave in the order they came (jitter never reorders).

Run as ``python3 -m server_select.testbed.linkemu --scenario S --hosts HOSTS.json`` (root needed);
it prints ``ready <t0>`` (t0: scenario time zero, epoch seconds) once every device is up,
and stops on SIGINT/SIGTERM, which deletes the devices. With ``--hold`` it prints ``ready
held`` instead and keeps every link as the scenario has it at time zero until a line ``go``
comes on its standard input; then it prints ``clock <t0>``: a scenario's time may start once
its nodes are up, not when their hosts are.
"""

import argparse
import ctypes
import errno
import fcntl
import heapq
import json
import os
import random
import select
import signal
import socket
import struct
import subprocess
import sys
import threading
import time

from server_select.testbed.scenario import Scenario, ScenarioError

TUNSETIFF = 0x400454ca
IFF_TUN = 0x0001
IFF_NO_PI = 0x1000
MTU = 65000
# The last this-many seconds before a packet is due are polled, not slept: a sleeping
# select() wakes 50-100 us late, a poll loop a few us.
SPIN = 0.0003


class EmulatorError(RuntimeError):
    """The emulator cannot run (no root, no TUN support, bad host map)."""


def open_tun(name):
    """A non-blocking TUN device ``name`` (deleted when the descriptor closes)."""
    try:
        fd = os.open('/dev/net/tun', os.O_RDWR | os.O_NONBLOCK)
    except OSError as error:
        raise EmulatorError('cannot open /dev/net/tun (%s): TUN support and root are needed'
                            % error.strerror)
    try:
        fcntl.ioctl(fd, TUNSETIFF, struct.pack('16sH', name.encode(), IFF_TUN | IFF_NO_PI))
    except OSError as error:
        os.close(fd)
        raise EmulatorError('cannot create TUN device %s: %s' % (name, error.strerror))
    return fd


def reduce_timer_slack():
    """Ask the kernel for 1 us timer slack (default 50 us) so delays end on time."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(29, 1, 0, 0, 0)  # PR_SET_TIMERSLACK
    except (OSError, AttributeError):
        pass


def ip(*args):
    subprocess.run(('ip',) + args, check=True, stdout=subprocess.DEVNULL)


class LinkEmulator(object):
    """Per-pair delay between hosts, each host a TUN device in its own namespace.

    ``hosts`` maps host name to ``{'netns': ..., 'address': ..., 'device': ...}``.
    ``clock`` is scenario time: seconds since ``t0``.
    """

    def __init__(self, scenario, hosts, seed=0, prefix_len=24):
        self.scenario = scenario
        self.hosts = hosts
        self.prefix_len = prefix_len
        self.rng = random.Random(seed)
        self.fds = {}
        self.host_of_fd = {}
        self.fd_of_address = {}
        self.heap = []
        self.last_due = {}
        self.free_at = {}
        self.seq = 0
        self.stats = {}
        self.t0_mono = None

    def setup(self):
        """Create every TUN device, move it into its host's namespace, address it."""
        for name, host in self.hosts.items():
            fd = open_tun(host['device'])
            self.fds[name] = fd
            self.host_of_fd[fd] = name
            self.fd_of_address[socket.inet_aton(host['address'])] = fd
            ip('link', 'set', host['device'], 'netns', host['netns'])
            ip('-n', host['netns'], 'addr', 'add', '%s/%d' % (host['address'], self.prefix_len),
               'dev', host['device'])
            ip('-n', host['netns'], 'link', 'set', host['device'], 'mtu', str(MTU), 'up')

    def start_clock(self):
        self.t0_mono = time.monotonic()
        return time.time()

    def _stat(self, src, dst):
        key = '%s>%s' % (src, dst)
        if key not in self.stats:
            self.stats[key] = {'forwarded': 0, 'lost': 0, 'down': 0, 'bytes': 0}
        return self.stats[key]

    def receive(self, fd, now):
        """Read every pending packet of one host and schedule its delivery."""
        src = self.host_of_fd[fd]
        while True:
            try:
                packet = os.read(fd, MTU + 100)
            except BlockingIOError:
                return
            except OSError as error:
                if error.errno in (errno.EAGAIN, errno.EINTR):
                    return
                raise
            if len(packet) < 20 or packet[0] >> 4 != 4:
                continue  # not IPv4 (IPv6 is off in the namespaces)
            dst_fd = self.fd_of_address.get(packet[16:20])
            if dst_fd is None:
                continue
            dst = self.host_of_fd[dst_fd]
            state = self.scenario.link(   # time stands at 0 until the clock starts
                src, dst, 0.0 if self.t0_mono is None else now - self.t0_mono)
            stat = self._stat(src, dst)
            if state.down:
                stat['down'] += 1
                continue
            if state.loss and self.rng.random() < state.loss:
                stat['lost'] += 1
                continue
            delay = state.delay
            if state.jitter:
                delay = max(0.0, delay + self.rng.uniform(-state.jitter, state.jitter))
            sent = now
            if state.rate:   # the link is busy until the packets before this one are out
                sent = max(now, self.free_at.get((src, dst), 0.0)) + \
                    len(packet) / (state.rate * 1e6)
                self.free_at[(src, dst)] = sent
            due = max(sent + delay / 1000.0, self.last_due.get((src, dst), 0.0))
            self.last_due[(src, dst)] = due
            self.seq += 1
            heapq.heappush(self.heap, (due, self.seq, dst_fd, packet))
            stat['forwarded'] += 1
            stat['bytes'] += len(packet)

    def deliver(self, now):
        while self.heap and self.heap[0][0] <= now:
            _, _, fd, packet = heapq.heappop(self.heap)
            try:
                os.write(fd, packet)
            except OSError:
                pass  # the destination's queue is full or it is gone: the packet is lost

    def run(self, should_stop=lambda: False):
        """Forward until ``should_stop()`` (checked at least every 0.1 s) is true."""
        fds = list(self.fds.values())
        while not should_stop():
            now = time.monotonic()
            timeout = 0.1 if not self.heap else max(0.0, min(0.1, self.heap[0][0] - now - SPIN))
            try:
                ready, _, _ = select.select(fds, [], [], timeout)
            except InterruptedError:
                ready = []
            now = time.monotonic()
            for fd in ready:
                self.receive(fd, now)
            self.deliver(time.monotonic())

    def close(self):
        for fd in self.fds.values():
            try:
                os.close(fd)
            except OSError:
                pass
        self.fds.clear()


def _start_on_go(emulator):
    """Start ``emulator``'s clock when stdin's line says ``go``; say its t0."""
    if sys.stdin.readline().strip() == 'go':
        print('clock %.6f' % emulator.start_clock(), flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--scenario', required=True, help='scenario YAML file')
    parser.add_argument('--hosts', required=True,
                        help='JSON: {host: {netns, address, device}}')
    parser.add_argument('--stats', help='write per-direction packet counts here (JSON)')
    parser.add_argument('--seed', type=int, default=0, help='jitter/loss random seed')
    parser.add_argument('--hold', action='store_true',
                        help='links as at time zero until "go" on stdin (then: clock <t0>)')
    args = parser.parse_args(argv)
    try:
        scenario = Scenario.load(args.scenario)
        with open(args.hosts) as stream:
            hosts = json.load(stream)
        unknown = set(hosts) - set(scenario.hosts)
        if unknown:
            raise EmulatorError('hosts not in the scenario: %s' % sorted(unknown))
        emulator = LinkEmulator(scenario, hosts, seed=args.seed)
        emulator.setup()
    except (ScenarioError, EmulatorError, OSError, subprocess.CalledProcessError) as error:
        print('linkemu: %s' % error, file=sys.stderr, flush=True)
        return 1
    reduce_timer_slack()
    stop = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.append(True))
    if args.hold:
        print('ready held', flush=True)
        threading.Thread(target=_start_on_go, args=(emulator,), daemon=True).start()
    else:
        print('ready %.6f' % emulator.start_clock(), flush=True)
    try:
        emulator.run(lambda: bool(stop))
    finally:
        emulator.close()
        if args.stats:
            with open(args.stats, 'w') as stream:
                json.dump(emulator.stats, stream, indent=1, sort_keys=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
