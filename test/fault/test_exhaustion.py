"""A server fed inputs made to exhaust it, each from this process: a sort task of 1e7
values (40 MB), sort tasks of 100,000 values (the most one may hold) at 68 a second, 4096 x
4096 frames (50 MB each), PNGs of 0.9 MB that inflate to 30000 x
30000 pixels, a connection header claiming 4 GB followed by 40 MB of junk, probes naming
500,000 made-up task kinds.

Each is refused from the length that precedes it, before it is read: the server stays
under 150 MiB, its probes are answered as fast as before (within 2 ms), a good task sent
after it is answered, and its log names the sender and the limit. (Before: 805 MiB after
two such tasks, 1,163 MiB after three frames, 62 CPU-s burnt on the header.)
"""

import os
import socket
import statistics
import struct
import subprocess
import threading
import time
import urllib.parse
import xmlrpc.client
import zlib

import numpy as np
import pytest
import rosgraph
import rospy
from rospy.numpy_msg import numpy_msg
from sensor_msgs.msg import CompressedImage, Image

from server_select.core.util.procs import stat_fields, stop_group, wait_until
from server_select.msg import ImageTask, SortResult, SortTask
from server_select.srv import LatencyProbe, LatencyProbeRequest

from test_faults import show

SERVER = 7
MAX_RSS = 150 << 20
# a probe answered after the attack as before it, within this (s): on a quiet host both are
# 0.1-0.3 ms; beside the other test streams 1-2 ms. (Before: 14.9 ms after the header.)
PROBE_SLACK = 2e-3


def rss(pid):
    with open('/proc/%d/status' % pid) as stream:
        return next(int(line.split()[1]) << 10 for line in stream if line.startswith('VmRSS'))


def cpu_seconds(pid):
    fields = stat_fields('/proc/%d/stat' % pid)
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


class Server(object):
    """Server 7 run by rosrun (its log in ``log``), a probe client, and a publisher of
    each task kind on the topics it subscribes to."""

    def __init__(self, log):
        self.log = log
        with open(log, 'w') as stream:
            self.proc = subprocess.Popen(
                ['rosrun', 'server_select', 'server', '_server_id:=%d' % SERVER,
                 '__name:=server%d' % SERVER], stdout=stream, stderr=subprocess.STDOUT,
                start_new_session=True, env=dict(os.environ, PYTHONUNBUFFERED='1'))
        self.service = '/latency_S%d' % SERVER
        rospy.wait_for_service(self.service, 30.0)
        self.probe = rospy.ServiceProxy(self.service, LatencyProbe, persistent=True)
        self.sort = rospy.Publisher('/data', numpy_msg(SortTask), queue_size=10)
        self.image = rospy.Publisher('/task_image', ImageTask, queue_size=10)
        self.results = []
        self.sub = rospy.Subscriber('/processed_data', SortResult, self.results.append)
        assert wait_until(lambda: self.sort.get_num_connections() and
                          self.image.get_num_connections() and
                          self.sub.get_num_connections(), 20.0)

    def probe_times(self, count=50):
        times = []
        for seq in range(count):
            start = time.perf_counter()
            self.probe(LatencyProbeRequest(robot_id=1, seq=seq))
            times.append(time.perf_counter() - start)
        return times

    def answers_a_task(self, task_id):
        self.sort.publish(numpy_msg(SortTask)(robot_id=1, task_id=task_id, server_id=SERVER,
                                              data=np.array([3, 1, 2], np.int32)))
        return wait_until(lambda: any(r.task_id == task_id and r.ok for r in self.results),
                          10.0)

    def lines(self, text):
        with open(self.log) as stream:
            return [line.strip() for line in stream if text in line]

    def tcpros_address(self):
        uri = rosgraph.Master(rospy.get_name()).lookupService(self.service)
        parsed = urllib.parse.urlparse(uri)
        return parsed.hostname, parsed.port

    def close(self):
        self.probe.close()
        for endpoint in (self.sort, self.image, self.sub):
            endpoint.unregister()
        stop_group(self.proc)


@pytest.fixture
def server(ros):
    started = Server(os.path.join(os.path.dirname(ros['log']), 'server7.log'))
    yield started
    started.close()


def attack(server, name, send):
    """Figures before and after ``send()``; the server must keep them within bounds."""
    pid = server.proc.pid
    before = statistics.median(server.probe_times())
    rss_before, cpu_before = rss(pid), cpu_seconds(pid)
    sent = send()
    time.sleep(1.0)          # what the server does with it, seen by its figures after
    after = server.probe_times()
    figures = {'input': name, 'sent': sent, 'RSS MiB before': rss_before >> 20,
               'RSS MiB after': rss(pid) >> 20,
               'server CPU s meanwhile': round(cpu_seconds(pid) - cpu_before, 2),
               'probe median ms before': round(1e3 * before, 3),
               'probe median ms after': round(1e3 * statistics.median(after), 3),
               'probe max ms after': round(1e3 * max(after), 3)}
    show('server %d attacked:' % SERVER, [figures])
    assert rss(pid) < MAX_RSS, figures
    assert statistics.median(after) < before + PROBE_SLACK, figures
    assert server.answers_a_task(len(name)), 'no good task answered after it'
    return figures


def test_oversized_sort_tasks_are_refused_unread(server):
    values = np.arange(10 ** 7, 0, -1, dtype=np.int32)

    def send():
        for task_id in (101, 102):
            server.sort.publish(numpy_msg(SortTask)(robot_id=66, task_id=task_id,
                                                    server_id=SERVER, data=values))
        return '2 tasks of 1e7 values'
    attack(server, 'sort tasks of 40 MB', send)
    assert wait_until(lambda: server.lines('refused a message of 40000'), 5.0)
    line = server.lines('refused a message of 40000')[0]
    assert rospy.get_name() in line and 'limit of 404096' in line, line


def test_a_flood_of_the_largest_sort_tasks_holds_no_memory(server):
    """Sort tasks of 100,000 values (the most a sort task may hold), 68 a second for 5 s:
    what the server cannot do in time is answered busy, it stays under 150 MiB all the
    while, and once it has worked off its queue its probes are as fast as before. (Before:
    rospy read each task connection 16 MiB at a time, and the server grew from 39 to
    200-390 MiB.)"""
    pid, values = server.proc.pid, np.arange(100000, 0, -1, dtype=np.int32)
    before = statistics.median(server.probe_times())
    sizes, sent, end = [rss(pid)], 0, time.monotonic() + 5.0
    while time.monotonic() < end:
        sent += 1
        server.sort.publish(numpy_msg(SortTask)(robot_id=66, task_id=1000 + sent,
                                                server_id=SERVER, data=values, budget=2.0))
        sizes.append(rss(pid))
        time.sleep(1.0 / 68)
    drained = wait_until(lambda: max(sizes.append(rss(pid)) or 0, statistics.median(
        server.probe_times(10))) < before + PROBE_SLACK, 30.0, period=0.5)
    figures = {'sent': '%d sort tasks of 100,000 values in 5 s' % sent,
               'RSS MiB before, most, after': (sizes[0] >> 20, max(sizes) >> 20,
                                               rss(pid) >> 20),
               'answered busy': len([r for r in server.results if not r.ok]),
               'probes as fast as before once drained': drained}
    show('server %d flooded:' % SERVER, [figures])
    assert max(sizes) < MAX_RSS, figures
    assert drained, figures
    assert server.answers_a_task(7), 'no good task answered after it'


def test_oversized_frames_are_refused_unread(server):
    frame = Image(height=4096, width=4096, encoding='bgr8', step=3 * 4096,
                  data=bytes(3 * 4096 * 4096))

    def send():
        for task_id in (201, 202, 203):
            server.image.publish(ImageTask(robot_id=66, task_id=task_id, server_id=SERVER,
                                           image=frame))
        return '3 frames of 4096 x 4096'
    attack(server, 'frames of 16.7 MP', send)
    assert wait_until(lambda: server.lines('on /task_image from %s' % rospy.get_name()), 5.0)


def png_bomb(side=30000):
    """A grayscale PNG of ``side`` x ``side`` zero pixels (900 MB inflated, about 0.9 MB)."""
    def chunk(kind, payload):
        return struct.pack('>I', len(payload)) + kind + payload + \
            struct.pack('>I', zlib.crc32(kind + payload))
    packer, row, parts = zlib.compressobj(9), b'\x00' * (side + 1), []
    for _ in range(side):
        parts.append(packer.compress(row))
    parts.append(packer.flush())
    header = struct.pack('>IIBBBBB', side, side, 8, 0, 0, 0, 0)
    return b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', header) + chunk(b'IDAT', b''.join(parts)) + \
        chunk(b'IEND', b'')


def test_a_png_that_inflates_to_900_mb_is_refused_from_its_header(server):
    bomb = png_bomb()

    def send():
        for task_id in (301, 302, 303):
            server.image.publish(ImageTask(robot_id=67, task_id=task_id, server_id=SERVER,
                                           compressed=CompressedImage(format='png', data=bomb)))
        return '3 PNGs of %d KB, 30000 x 30000 pixels' % (len(bomb) >> 10)
    figures = attack(server, 'PNG bombs', send)
    assert wait_until(lambda: server.lines('30000x30000 exceeds max_image_pixels'), 10.0), \
        server.lines('robot 67')
    assert figures['server CPU s meanwhile'] < 5.0, figures


def test_a_header_claiming_4_gb_ends_its_connection(server):
    def send():
        sock = socket.create_connection(server.tcpros_address(), 5.0)
        sent = 0
        try:
            sock.sendall(struct.pack('<I', 2 ** 32 - 1))
            junk = bytes(1 << 20)
            for _ in range(40):
                sock.sendall(junk)
                sent += len(junk)
        except OSError:        # closed by the server: what is wanted
            pass
        finally:
            sock.close()
        return '%d MB of the 40 MB of junk taken before the server closed' % (sent >> 20)
    figures = attack(server, 'a header of 4 GB', send)
    assert figures['server CPU s meanwhile'] < 1.0, figures
    assert server.lines('connection header of 4294967295 bytes')


def test_probes_naming_made_up_kinds_cost_nothing(server):
    kinds = ['kind%d' % i for i in range(5000)]

    def send():
        probe, refused = rospy.ServiceProxy(server.service, LatencyProbe), 0
        for seq in range(100):
            try:
                probe(LatencyProbeRequest(robot_id=1, seq=seq, task_kinds=kinds,
                                          task_rates=[1e6] * len(kinds)))
            except rospy.ServiceException as error:
                refused += 'request refused' in str(error)
        assert refused == 100, '%d of 100 probes refused' % refused
        return '100 probes of 5,000 kinds each, each refused with the reason'
    attack(server, 'probes with 500,000 made-up kinds', send)
    assert server.lines('on %s from %s' % (server.service, rospy.get_name()))


def test_idle_sockets_hold_no_new_connection(server):
    """Peers that connect to the server's TCPROS port and send nothing: a new connection
    (a probe over a fresh one) is answered within 1 s meanwhile, and each idle socket is
    closed once its handshake's deadline passes. (Before: rospy read every handshake on its
    one accept thread, and the probe waited as long as the idle socket stayed open.)"""
    idle = [socket.create_connection(server.tcpros_address(), 5.0) for _ in range(5)]
    answered, took = [], []

    def probe():
        start = time.perf_counter()
        rospy.ServiceProxy(server.service, LatencyProbe)(LatencyProbeRequest(robot_id=1))
        took.append(time.perf_counter() - start)
        answered.append(True)
    try:
        caller = threading.Thread(target=probe, daemon=True)
        caller.start()
        caller.join(5.0)
        closed = 0
        for sock in idle:
            sock.settimeout(5.0)
            try:
                closed += sock.recv(1) == b''
            except socket.timeout:  # still open
                pass
            except OSError:         # reset: closed too
                closed += 1
        show('idle sockets on server %d:' % SERVER, [{
            'idle sockets': len(idle), 'probe over a new connection answered': bool(answered),
            'its round trip ms': round(1e3 * took[0], 1) if took else None,
            'idle sockets closed by the server': closed}])
        assert answered and took[0] < 1.0, took
        assert closed == len(idle)
        assert wait_until(lambda: server.lines('no handshake within 2 s'), 5.0)
    finally:
        for sock in idle:
            sock.close()


def threads(pid):
    with open('/proc/%d/status' % pid) as stream:
        return next(int(line.split()[1]) for line in stream if line.startswith('Threads'))


def test_half_written_xmlrpc_requests_hold_a_bounded_number_of_threads(server):
    """1,000 peers that each send half an HTTP request to the server's XML-RPC port: the
    server serves at most MOST_AT_ONCE at once and closes the rest, closes the ones it
    serves at their deadline, answers a new call once they are closed, and goes on
    answering probes meanwhile. (Before: a thread each, 24 -> 1,024, for as long as the
    peers held them.)"""
    from server_select.ros.xmlrpc_bound import DEADLINE, MOST_AT_ONCE
    pid = server.proc.pid
    uri = urllib.parse.urlparse(rosgraph.Master(rospy.get_name()).lookupNode('/server7'))
    before = threads(pid)
    t_start = time.monotonic()
    held = []
    for _ in range(1000):
        sock = socket.create_connection((uri.hostname, uri.port), 5.0)
        sock.sendall(b'POST /RPC2 HTTP/1.1\r\nContent-Length: 500\r\n')
        held.append(sock)
    try:
        most = max(threads(pid) for _ in range(20) if time.sleep(0.05) is None)
        probes = server.probe_times(10)

        def open_ones():
            alive = 0
            for sock in held:
                sock.settimeout(0.0)
                try:
                    alive += sock.recv(1) != b''
                except BlockingIOError:      # nothing to read: still open
                    alive += 1
                except OSError:              # reset: closed
                    pass
            return alive
        closed_all = wait_until(lambda: open_ones() == 0, DEADLINE + 5.0)
        t_closed = time.monotonic() - t_start
        proxy = xmlrpc.client.ServerProxy(uri.geturl())
        answered = proxy.getPid('/fault_tests')[2] == pid
        show('1,000 half-written XML-RPC requests to server %d:' % SERVER, [{
            'threads before': before, 'most threads meanwhile': most,
            'probe max ms meanwhile': round(1e3 * max(probes), 2),
            'every connection closed after s': round(t_closed, 1) if closed_all else 'never',
            'a new call answered': answered, 'threads after': threads(pid)}])
        assert most <= before + MOST_AT_ONCE + 4, most
        assert closed_all and answered
        assert wait_until(lambda: server.lines('closed an XML-RPC connection'), 5.0)
    finally:
        for sock in held:
            sock.close()
