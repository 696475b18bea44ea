"""The emulator's scheduling, with pipes standing in for TUN devices (no root needed)."""
import os
import socket
import struct

import pytest

from server_select.testbed.linkemu import LinkEmulator
from server_select.testbed.scenario import Scenario

ADDR = {'a': '10.231.0.1', 'b': '10.231.0.2'}


def packet(src, dst, tag):
    header = struct.pack('!BBHHHBBH4s4s', 0x45, 0, 20 + len(tag), 0, 0, 64, 17, 0,
                         socket.inet_aton(ADDR[src]), socket.inet_aton(ADDR[dst]))
    return header + tag


def emulator(link_events, seed=0):
    sc = Scenario({'hosts': {'a': {'role': 'manager'}, 'b': {'role': 'server', 'id': 1}},
                   'links': {'a b': link_events}})
    emu = LinkEmulator(sc, {}, seed=seed)
    pipes = {}
    for name in ('a', 'b'):
        r_in, w_in = os.pipe()      # what the host "sends": the emulator reads r_in
        r_out, w_out = os.pipe()    # what the emulator delivers to the host
        os.set_blocking(r_in, False)
        os.set_blocking(r_out, False)
        pipes[name] = (w_in, r_out)
        emu.fds[name] = r_in
        emu.host_of_fd[r_in] = name
        emu.fd_of_address[socket.inet_aton(ADDR[name])] = w_out
        emu.host_of_fd[w_out] = name
    emu.t0_mono = 0.0
    return emu, pipes


def delivered(pipes, name):
    try:
        return os.read(pipes[name][1], 1 << 16)
    except BlockingIOError:
        return b''


def test_packet_is_held_for_the_one_way_delay():
    emu, pipes = emulator([{'at': 0, 'delay': 10}])
    os.write(pipes['a'][0], packet('a', 'b', b'x'))
    emu.receive(emu.fds['a'], now=1.0)
    emu.deliver(1.0099)
    assert delivered(pipes, 'b') == b''
    emu.deliver(1.0100)
    assert delivered(pipes, 'b') == packet('a', 'b', b'x')
    assert emu.stats['a>b']['forwarded'] == 1


def test_delay_follows_scenario_time_and_jitter_never_reorders():
    emu, pipes = emulator([{'at': 0, 'delay': 50}, {'at': 5, 'delay': 1, 'jitter': 1}])
    os.write(pipes['a'][0], packet('a', 'b', b'1'))
    emu.receive(emu.fds['a'], now=4.999)          # due at 5.049
    for i in range(2, 30):
        os.write(pipes['a'][0], packet('a', 'b', b'%d' % i))
        emu.receive(emu.fds['a'], now=5.0 + i * 1e-4)   # delay 0..2 ms, but FIFO
    dues = sorted(item[0] for item in emu.heap)
    assert dues[0] == pytest.approx(5.049)   # nothing overtakes the slow first packet
    emu.deliver(10.0)
    data = b''
    while True:
        chunk = delivered(pipes, 'b')
        if not chunk:
            break
        data += chunk
    tags = []
    while data:
        length = struct.unpack('!H', data[2:4])[0]
        tags.append(data[20:length])
        data = data[length:]
    assert tags == [b'%d' % i for i in range(1, 30)]
    assert dues[-1] == pytest.approx(5.049)


def test_down_and_loss_drop_packets():
    emu, pipes = emulator([{'at': 0, 'down': True}, {'at': 10, 'down': False, 'loss': 0.5}],
                          seed=3)
    os.write(pipes['a'][0], packet('a', 'b', b'd'))
    emu.receive(emu.fds['a'], now=1.0)
    assert emu.heap == [] and emu.stats['a>b']['down'] == 1
    for _ in range(400):
        os.write(pipes['b'][0], packet('b', 'a', b'l'))
        emu.receive(emu.fds['b'], now=11.0)
    lost = emu.stats['b>a']['lost']
    assert 150 < lost < 250 and emu.stats['b>a']['forwarded'] == 400 - lost


def test_non_ipv4_and_unknown_destinations_are_ignored():
    emu, pipes = emulator([{'at': 0, 'delay': 1}])
    os.write(pipes['a'][0], b'\x60' + b'\x00' * 39)   # IPv6
    emu.receive(emu.fds['a'], now=0.0)
    stray = bytearray(packet('a', 'b', b'z'))
    stray[16:20] = socket.inet_aton('10.231.0.99')
    os.write(pipes['a'][0], bytes(stray))
    emu.receive(emu.fds['a'], now=0.0)
    assert emu.heap == []


def test_a_rate_limit_spaces_packets_by_their_size():
    emu, pipes = emulator([{'at': 0, 'delay': 10, 'rate': 0.001}])   # 1 kB/s each way
    first, second = packet('a', 'b', b'x' * 80), packet('a', 'b', b'y' * 80)   # 100 bytes
    for tag in (first, second):              # one packet per read, as from a TUN device
        os.write(pipes['a'][0], tag)
        emu.receive(emu.fds['a'], now=1.0)
    emu.deliver(1.1098)
    assert delivered(pipes, 'b') == b''
    emu.deliver(1.1101)                     # 0.1 s on the wire + 10 ms
    assert delivered(pipes, 'b') == first
    emu.deliver(1.2098)
    assert delivered(pipes, 'b') == b''
    emu.deliver(1.2101)                     # queued behind the first
    assert delivered(pipes, 'b') == second
    assert emu.stats['a>b']['bytes'] == 200


def test_a_held_clock_keeps_the_links_as_at_time_zero_until_it_starts(monkeypatch):
    emu, pipes = emulator([{'at': 0, 'delay': 10}, {'at': 1, 'down': True}])
    emu.t0_mono = None      # --hold: no clock yet, however long the nodes take to come up
    os.write(pipes['a'][0], packet('a', 'b', b'held'))
    emu.receive(emu.fds['a'], now=100.0)
    assert emu.stats['a>b'] == {'forwarded': 1, 'lost': 0, 'down': 0, 'bytes': 24}
    monkeypatch.setattr('time.monotonic', lambda: 100.0)
    emu.start_clock()       # time 0 now: the link goes down 1 s later
    for now, counted in ((100.5, 'forwarded'), (101.5, 'down')):
        os.write(pipes['a'][0], packet('a', 'b', b'x'))
        emu.receive(emu.fds['a'], now=now)
        assert emu.stats['a>b'][counted] == (2 if counted == 'forwarded' else 1), emu.stats
