"""Raw TCP socket round trips, the yardstick for ROS and for the link emulator.

Frames are a 4-byte big-endian length and the payload. ``echo_server`` sends every frame
back; ``echo_client`` times ``count`` round trips. Command line (used inside testbed
hosts)::

    python3 -m server_select.bench.netbench echo-server --port 5555
    python3 -m server_select.bench.netbench echo-client --host 10.231.0.2 --port 5555 --count 200
    python3 -m server_select.bench.netbench probe-client --server-id 1 --count 100  # a master

Clients print one JSON object: ``{"rtt": [seconds, ...], ...}``.
"""

import argparse
import json
import socket
import struct
import sys
import time

from server_select.bench import cli
from server_select.core.util.procs import wait_until
HEADER = struct.Struct('!I')


def recv_exact(sock, size):
    chunks, remaining = [], size
    while remaining:
        chunk = sock.recv(min(remaining, 1 << 20))
        if not chunk:
            raise ConnectionError('peer closed the connection')
        chunks.append(chunk)
        remaining -= len(chunk)
    return b''.join(chunks)


def recv_frame(sock):
    (size,) = HEADER.unpack(recv_exact(sock, HEADER.size))
    return recv_exact(sock, size)


def send_frame(sock, payload):
    sock.sendall(HEADER.pack(len(payload)) + payload)


def echo_server(port, host='0.0.0.0', nodelay=True, ready=None, max_connections=None):
    """Serve echo connections one after another (``max_connections``: then return)."""
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind((host, port))
    listener.listen(4)
    if ready:
        ready(listener.getsockname()[1])
    served = 0
    try:
        while max_connections is None or served < max_connections:
            conn, _ = listener.accept()
            served += 1
            if nodelay:
                conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            with conn:
                try:
                    while True:
                        send_frame(conn, recv_frame(conn))
                except ConnectionError:
                    pass
    finally:
        listener.close()


def connect(host, port, timeout=10.0, nodelay=True):
    """A connection to host:port, retried until ``timeout`` (the server may be starting)."""
    sockets = []

    def attempt():
        try:
            sockets.append(socket.create_connection((host, port), timeout=timeout))
        except OSError:
            return False
        return True
    if not wait_until(attempt, timeout):
        raise ConnectionError('cannot connect to %s:%d within %.0f s' % (host, port, timeout))
    sock = sockets[0]
    sock.settimeout(None)
    if nodelay:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


def echo_client(host, port, count, size=4, interval=0.01, warmup=5, nodelay=True):
    """Round trips (seconds) of ``count`` frames of ``size`` bytes, ``interval`` apart."""
    sock = connect(host, port, nodelay=nodelay)
    payload = b'x' * size
    rtts = []
    with sock:
        for i in range(warmup + count):
            start = time.perf_counter()
            send_frame(sock, payload)
            if len(recv_frame(sock)) != size:
                raise ConnectionError('echo returned a different size')
            if i >= warmup:
                rtts.append(time.perf_counter() - start)
            time.sleep(interval)
    return rtts


def probe_client(server_id, count, interval=0.05, timeout=1.0, warmup=3):
    """LatencyProbe round trips through the package's own persistent, timed proxy."""
    import rospy
    from server_select.core.config import names
    from server_select.ros.probe_client import TimedServiceProxy
    from server_select.srv import LatencyProbe, LatencyProbeRequest
    rospy.init_node('probe_bench', anonymous=True, disable_signals=True)
    service = names.probe_service(server_id)
    rospy.wait_for_service(service, 30.0)
    proxy = TimedServiceProxy(service, LatencyProbe)
    rtts, failed = [], 0
    for i in range(warmup + count):
        request = LatencyProbeRequest(robot_id=0, seq=i, stamp=rospy.Time.now())
        try:
            _, rtt = proxy.call_within(request, timeout)
            if i >= warmup:
                rtts.append(rtt)
        except rospy.ServiceException:
            failed += 1
        time.sleep(interval)
    proxy.close()
    return rtts, failed


def main(argv=None):
    parser = argparse.ArgumentParser(description='raw TCP and LatencyProbe round trips')
    sub = parser.add_subparsers(dest='command', required=True)
    server = sub.add_parser('echo-server')
    server.add_argument('--port', type=int, required=True)
    server.add_argument('--nagle', action='store_true', help='leave Nagle on')
    client = cli.messages(sub.add_parser('echo-client'), count=200)
    client.add_argument('--host', required=True)
    client.add_argument('--port', type=int, required=True)
    client.add_argument('--nagle', action='store_true', help='leave Nagle on')
    probe = sub.add_parser('probe-client')
    probe.add_argument('--server-id', type=int, required=True)
    probe.add_argument('--count', type=int, default=100)
    probe.add_argument('--interval', type=float, default=0.05)
    args = parser.parse_args(argv)
    if args.command == 'echo-server':
        echo_server(args.port, nodelay=not args.nagle,
                    ready=lambda port: print('listening %d' % port, flush=True))
    elif args.command == 'echo-client':
        rtts = echo_client(args.host, args.port, args.count, args.size, args.interval,
                           nodelay=not args.nagle)
        print(json.dumps({'rtt': rtts}))
    else:
        rtts, failed = probe_client(args.server_id, args.count, args.interval)
        print(json.dumps({'rtt': rtts, 'failed': failed}))
    return 0


if __name__ == '__main__':
    sys.exit(main())
