#!/usr/bin/env python3
"""A node without the fleet key (or with one role's key) attacking a keyed fleet.

    attacker.py MODE SECONDS [ROLE_KEY_FILE]

``tasks``: sort tasks under made-up robot ids, 20 a second to each of servers 1-3.
``rates``: probes of servers 1-3 under a made-up robot id announcing 1e6 sort tasks a
second, 20 a second each. ``results``: registers ``/latency_S1..3`` at the master itself
and publishes a junk result for every task of robot 1, once a second. ``announce`` (a
server's key): registers ``/latency_S2`` at the master and announces server 2 there, then
leaves. ``namespace`` (a
robot's key; run in ``/robot2``, as ``/robot2/attacker``): rankings of robot 2 naming
server 3 and failed task reports of robot 2, 20 a second. ``flood`` (a robot's key): robot
9, admitted by a sealed probe of each server every second, sends 100,000-value sort tasks
to servers 1-3 in turn, 68 a second, ignoring every answer. ``lapsed`` (a robot's key):
robot 9 bound at server 8 by one sealed probe, silent until its lease has ended, then sort
tasks there, 20 a second. ``spoof``: sort tasks of robot 1
to servers 1-3, 20 a second each, over connections whose header claims ``callerid
/robot1`` (rospy lets a publisher override its header's fields). ``callerids``: 1,300
connections to servers 1-3 in turn, each with a header claiming a new callerid of 900 KB:
every other one names the server's probe service and sends a probe of 100 KB (its limit is
64 KiB), the others a service the server does not have; each until refused.
``announcement``: one unsigned ServerAnnouncement of 150 MB.

Prints what it sent as one line of JSON.
"""

import json
import random
import socket
import struct
import sys
import time
import xmlrpc.client

import numpy as np
import rosgraph
from rosgraph.network import encode_ros_handshake_header
import rospy
from rospy.numpy_msg import numpy_msg

from server_select.core.config import names
from server_select.core.fleet.leases import LEASE_PERIODS
from server_select.core.trust.seal import Sealer, load_keys
from server_select.ros.robot_admission import ROBOT_LEASE
from server_select.msg import RobotRanking, ServerAnnouncement, SortResult, SortTask, TaskReport
from server_select.ros.seal import sealed
from server_select.srv import LatencyProbe, LatencyProbeRequest, LatencyProbeResponse

SERVERS = (1, 2, 3)
MADE_UP = 66
FLOODER = 9


def tasks(seconds, _sealer):
    pubs = [rospy.Publisher(names.server_topic(s, names.SORT_TASK_TOPIC), numpy_msg(SortTask),
                            queue_size=100) for s in SERVERS]
    time.sleep(1.0)
    sent, end, task_id = 0, time.monotonic() + seconds, 0
    while time.monotonic() < end:
        task_id += 1
        for server, pub in zip(SERVERS, pubs):
            pub.publish(numpy_msg(SortTask)(robot_id=MADE_UP + task_id % 50, task_id=task_id,
                                            server_id=server,
                                            data=np.arange(1000, 0, -1, dtype=np.int32)))
            sent += 1
        time.sleep(0.05)
    return {'tasks': sent}


def spoof(seconds, _sealer):
    pubs = [rospy.Publisher(names.server_topic(s, names.SORT_TASK_TOPIC), numpy_msg(SortTask),
                            queue_size=100, headers={'callerid': '/robot1'}) for s in SERVERS]
    time.sleep(1.0)
    sent, end, task_id = 0, time.monotonic() + seconds, 10 ** 6
    while time.monotonic() < end:
        task_id += 1
        for server, pub in zip(SERVERS, pubs):
            pub.publish(numpy_msg(SortTask)(robot_id=1, task_id=task_id, server_id=server,
                                            data=np.arange(1000, 0, -1, dtype=np.int32)))
            sent += 1
        time.sleep(0.05)
    return {'tasks as robot 1': sent}


def rates(seconds, _sealer):
    proxies = [rospy.ServiceProxy(names.probe_service(s), LatencyProbe, persistent=True)
               for s in SERVERS]
    sent, end = 0, time.monotonic() + seconds
    while time.monotonic() < end:
        for proxy in proxies:
            try:
                proxy(LatencyProbeRequest(robot_id=MADE_UP, seq=sent, task_kinds=['sort'],
                                          task_rates=[1e6]))
                sent += 1
            except rospy.ServiceException:
                pass
        time.sleep(0.05)
    return {'probes': sent}


def results(seconds, _sealer):
    def answer(req):
        return LatencyProbeResponse(server_id=0, seq=req.seq, stamp=req.stamp)
    services = [rospy.Service(names.probe_service(s), LatencyProbe, answer) for s in SERVERS]
    pub = rospy.Publisher(names.robot_topic(1, names.SORT_RESULT_TOPIC), SortResult,
                          queue_size=10)
    sent, end = 0, time.monotonic() + seconds
    while time.monotonic() < end:
        pub.publish(SortResult(robot_id=1, task_id=sent, server_id=1, ok=True, data=[1]))
        sent += 1
        time.sleep(1.0)
    for service in services:
        service.shutdown()
    return {'results': sent}


def announce(seconds, sealer):
    def answer(req):
        return LatencyProbeResponse(server_id=2, seq=req.seq, stamp=req.stamp)
    service = rospy.Service(names.probe_service(2), LatencyProbe, answer)   # the master's
    pub = rospy.Publisher(names.ANNOUNCE_TOPIC, ServerAnnouncement, queue_size=10, latch=True)
    time.sleep(1.0)
    sent, end = 0, time.monotonic() + seconds
    while time.monotonic() < end:
        msg = ServerAnnouncement(server_id=2, lease=LEASE_PERIODS * 2.0, probe_uri=service.uri)
        msg.header.stamp = rospy.Time.now()
        pub.publish(sealed(msg, sealer, pub.resolved_name))
        sent += 1
        time.sleep(1.0)
    leave = ServerAnnouncement(server_id=2, lease=0.0, probe_uri=service.uri)
    pub.publish(sealed(leave, sealer, pub.resolved_name))
    service.shutdown()
    time.sleep(0.5)
    return {'announcements': sent + 1}


def namespace(seconds, sealer):
    rankings = rospy.Publisher('/' + names.RANKINGS_TOPIC, RobotRanking, queue_size=100)
    reports = rospy.Publisher('/' + names.TASK_REPORT_TOPIC, TaskReport, queue_size=100)
    time.sleep(1.0)
    sent, end = 0, time.monotonic() + seconds
    while time.monotonic() < end:
        sent += 1
        ranking = RobotRanking(robot_id=2, ranking=[3, 1, 2], mean_latency=[1e-6, 1, 1],
                               error=[0, 0, 0], sample_count=[50, 50, 50], selected=3,
                               reason='forged')
        ranking.header.stamp = rospy.Time.now()
        rankings.publish(sealed(ranking, sealer, rankings.resolved_name))
        report = TaskReport(robot_id=2, task_id=100000 + sent, kind='sort', server_id=1,
                            answered_by=-1, ok=False, error='timeout', rtt=float('nan'))
        report.header.stamp = rospy.Time.now()
        reports.publish(sealed(report, sealer, reports.resolved_name))
        time.sleep(0.05)
    return {'rankings': sent, 'reports': sent}


def flood(seconds, sealer):
    proxies = [rospy.ServiceProxy(names.probe_service(s), LatencyProbe, persistent=True)
               for s in SERVERS]
    pubs = [rospy.Publisher(names.server_topic(s, names.SORT_TASK_TOPIC), numpy_msg(SortTask),
                            queue_size=100) for s in SERVERS]
    data = np.arange(100000, 0, -1, dtype=np.int32)
    nonce = random.Random()

    def admit(seq):
        for server, proxy in zip(SERVERS, proxies):
            request = LatencyProbeRequest(robot_id=FLOODER, seq=seq, stamp=rospy.Time.now(),
                                          nonce=nonce.getrandbits(64),
                                          node_uri=rospy.core.get_node_uri())
            try:
                proxy(sealed(request, sealer, rospy.resolve_name(names.probe_service(server))))
            except rospy.ServiceException:
                pass
    admit(1)
    time.sleep(1.0)
    sent, end, admitted = 0, time.monotonic() + seconds, time.monotonic()
    while time.monotonic() < end:
        if time.monotonic() - admitted > 1.0:
            admit(sent + 2)
            admitted = time.monotonic()
        index = sent % len(SERVERS)
        sent += 1
        pubs[index].publish(numpy_msg(SortTask)(robot_id=FLOODER, task_id=sent,
                                                server_id=SERVERS[index], data=data,
                                                budget=2.0))
        time.sleep(1.0 / 68)
    return {'sorts of 100,000 values': sent}


def lapsed(seconds, sealer, server=8):
    proxy = rospy.ServiceProxy(names.probe_service(server), LatencyProbe)
    request = LatencyProbeRequest(robot_id=FLOODER, seq=1, stamp=rospy.Time.now(),
                                  nonce=random.Random().getrandbits(64),
                                  node_uri=rospy.core.get_node_uri())
    proxy(sealed(request, sealer, rospy.resolve_name(names.probe_service(server))))
    pub = rospy.Publisher(names.server_topic(server, names.SORT_TASK_TOPIC),
                          numpy_msg(SortTask), queue_size=100)
    time.sleep(ROBOT_LEASE + 1.0)        # no sealed probe since: the lease has ended
    sent, end = 0, time.monotonic() + seconds
    while time.monotonic() < end:
        sent += 1
        pub.publish(numpy_msg(SortTask)(robot_id=FLOODER, task_id=sent, server_id=server,
                                        data=np.arange(1000, 0, -1, dtype=np.int32)))
        time.sleep(0.05)
    return {'tasks after the lease ended': sent}


def callerids(_seconds, _sealer, count=1300, callerid_bytes=900 * 1024):
    master = rosgraph.Master(rospy.get_name())
    addresses = []
    for server in SERVERS:
        # the server's TCPROS port, from the node itself: the master's listing of its probe
        # service may be gone (earlier attackers took it and left)
        node = xmlrpc.client.ServerProxy(master.lookupNode('/server%d' % server))
        _, _, (_, host, port) = node.requestTopic(
            rospy.get_name(), rospy.resolve_name(names.ANNOUNCE_TOPIC), [['TCPROS']])
        addresses.append((server, (host, port)))
    padding = 'x' * callerid_bytes
    probe = struct.pack('<I', 100 << 10) + b'\0' * (100 << 10)
    sent, refused = 0, {b'more than its limit': 0, b'is not a provider': 0}
    for index in range(count):
        server, address = addresses[index % len(addresses)]
        service = rospy.resolve_name(names.probe_service(server)) if index % 2 else '/not_here'
        header = encode_ros_handshake_header({
            'callerid': '/made_up_%d_%s' % (index, padding), 'service': service,
            'md5sum': LatencyProbe._md5sum, 'persistent': '1'})
        try:
            with socket.create_connection(address, 5.0) as sock:
                sock.sendall(header)
                sock.sendall(probe)
                sock.settimeout(5.0)
                answer = b''
                while not any(why in answer for why in refused):
                    chunk = sock.recv(65536)
                    if not chunk:
                        break
                    answer += chunk
            sent += 1
            for why in refused:
                refused[why] += why in answer
        except OSError:                        # reset, or no answer in 5 s
            pass
    return {'connections with a 900 KB callerid': sent,
            'refused: probe over its limit': refused[b'more than its limit'],
            'refused: no such service': refused[b'is not a provider']}


def announcement(seconds, _sealer, size=150 << 20):
    pub = rospy.Publisher(names.ANNOUNCE_TOPIC, ServerAnnouncement, queue_size=1)
    time.sleep(1.0)
    pub.publish(ServerAnnouncement(server_id=4, lease=LEASE_PERIODS * 2.0,
                                   probe_uri='x' * size))
    time.sleep(seconds)        # each subscriber reads past it: 150 MB apiece
    return {'unsigned announcements of 150 MB': 1}


MODES = dict((f.__name__, f) for f in (tasks, rates, results, announce, namespace, flood,
                                       spoof, callerids, announcement, lapsed))
ROLES = {'announce': 'server', 'namespace': 'robot', 'flood': 'robot', 'lapsed': 'robot'}


def main():
    mode, seconds = sys.argv[1], float(sys.argv[2])
    rospy.init_node('attacker', disable_signals=True)
    sealer = Sealer(load_keys(sys.argv[3], ROLES[mode]), rospy.get_name()) \
        if len(sys.argv) > 3 else None
    print(json.dumps(MODES[mode](seconds, sealer)), flush=True)


if __name__ == '__main__':
    main()
