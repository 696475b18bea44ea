"""ROS topic vs raw TCP socket one-way latency on one host (paper 2, Table 2).

A receiver process subscribes to a ROS topic and accepts one TCP connection; a sender
process alternates between the two (interleaved A/B: each ROS message is followed by a
socket message of the same payload), stamping each with CLOCK_MONOTONIC, which all
processes of a host share. The receiver computes arrival - stamp for each message.

    python3 -m server_select.bench.latency receiver --port P --count N [--nagle]
    python3 -m server_select.bench.latency sender --port P --count N --size S [--interval I]

The receiver prints one JSON object: ``{"ros": [s, ...], "socket": [s, ...]}``.
"""

import argparse
import json
import socket
import struct
import sys
import threading
import time

from server_select.core.util.procs import wait_until
from server_select.bench import cli
from server_select.bench.netbench import connect, recv_frame, send_frame

STAMP = struct.Struct('!d')
TOPIC = 'bench_payload'


def receiver(port, count, nodelay=True, warmup=20, timeout=120.0):
    """Latencies of ``count`` messages per path after ``warmup`` unmeasured ones."""
    import rospy
    from server_select.msg import BenchPayload
    rospy.init_node('latency_bench_receiver', anonymous=True, disable_signals=True)
    ros, sock_lat = [], []
    done = threading.Event()

    total = warmup + count

    def on_msg(msg):
        ros.append(time.monotonic() - msg.stamp)
        if len(ros) >= total and len(sock_lat) >= total:
            done.set()

    sub = rospy.Subscriber(TOPIC, BenchPayload, on_msg, queue_size=total + 10,
                           tcp_nodelay=nodelay, buff_size=1 << 24)
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(('127.0.0.1', port))
    listener.listen(1)
    print('ready', flush=True)
    conn, _ = listener.accept()
    if nodelay:
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    with conn:
        try:
            while len(sock_lat) < total:
                frame = recv_frame(conn)
                sock_lat.append(time.monotonic() - STAMP.unpack_from(frame)[0])
        except ConnectionError:
            pass
    if len(ros) >= total and len(sock_lat) >= total:
        done.set()
    done.wait(timeout)       # the topic's last messages may still be on their way
    sub.unregister()
    listener.close()
    return {'ros': ros[warmup:total], 'socket': sock_lat[warmup:total]}


def sender(port, count, size, interval, warmup=20):
    """Send ``warmup + count`` messages of ``size`` payload bytes on each path, alternating."""
    import rospy
    from server_select.msg import BenchPayload
    from server_select.ros.node import flush
    rospy.init_node('latency_bench_sender', anonymous=True, disable_signals=True)
    pub = rospy.Publisher(TOPIC, BenchPayload, queue_size=count + warmup + 10)
    if not wait_until(lambda: pub.get_num_connections() > 0, 30.0, period=0.01):
        raise RuntimeError('no subscriber connected to %s' % TOPIC)
    sock = connect('127.0.0.1', port)
    payload = bytes(size)
    with sock:
        for _ in range(warmup + count):
            pub.publish(BenchPayload(stamp=time.monotonic(), payload=payload))
            time.sleep(interval / 2)
            send_frame(sock, STAMP.pack(time.monotonic()) + payload)
            time.sleep(interval / 2)
    flush(pub, timeout=10.0)     # what rospy still queues would be lost with the process


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    sub = parser.add_subparsers(dest='command', required=True)
    rec = sub.add_parser('receiver')
    rec.add_argument('--port', type=int, required=True)
    rec.add_argument('--count', type=int, default=500)
    rec.add_argument('--nagle', action='store_true', help='tcp_nodelay off on both paths')
    snd = cli.messages(sub.add_parser('sender'), count=500)
    snd.add_argument('--port', type=int, required=True)
    args = parser.parse_args(argv)
    if args.command == 'receiver':
        print(json.dumps(receiver(args.port, args.count, nodelay=not args.nagle)), flush=True)
    else:
        sender(args.port, args.count, args.size, args.interval)
    return 0


if __name__ == '__main__':
    sys.exit(main())
