"""Robots that stop while a server connects to them leave the server nothing behind.

A robot stopping (SIGINT) answers a subscriber's handshake with "node shutting down"; a
server that was connecting to it right then (a publisher update in flight) gives the
connection up once the robot is gone. rospy alone kept that socket open (CLOSE-WAIT) and
the connection in its topic's list for good: in a run where one robot started and stopped
16 times, each server held 2-3 more descriptors at the end. Here each of 5 robots is a
stand-in that does just that: it registers as a publisher of the server's task topic at
the real master, answers the server's handshake with that error and says it publishes
nothing. Printed: how many connections the server made, closed, and still lists, and its
sockets to them it holds, and its descriptors before and after. Asserted: every connection
closed, none listed, no socket held, for 3 s on end within 30 s of the robots' leaving.
"""

import io
import os
import socket
import subprocess
import threading
import xmlrpc.client
import xmlrpc.server

import rosgraph
import rospy
from rosgraph.network import (ROSHandshakeException, encode_ros_handshake_header,
                              read_ros_handshake_header)

from server_select.core.config import names
from server_select.core.util.lasting import Lasting
from server_select.core.util.procs import stop_group, wait_until
from server_select.ros.graph import subscribers

from support.fleet import Fleet
from test_faults import show

SERVER = 7
TOPIC = '/' + names.server_topic(SERVER, names.SORT_TASK_TOPIC)
ROBOTS = 5
QUIET = 3.0     # s: longer than rospy's 1 s wait after a refused handshake, under load


class StoppingRobot(object):
    """A robot's XML-RPC API and TCPROS listener as they are while it stops: the topic is
    offered (``requestTopic``), every handshake refused, the topic no longer published
    (``getPublications``). Counted: the connections made to it and those the server then
    closed (rospy may make a second before the first is through, and drop the first)."""

    def __init__(self, name):
        self.name, self.lock, self.made, self.closed = name, threading.Lock(), 0, 0
        self.tcpros = socket.create_server(('127.0.0.1', 0))
        self.api = xmlrpc.server.SimpleXMLRPCServer(('127.0.0.1', 0), logRequests=False,
                                                    allow_none=True)
        self.api.register_function(self.request_topic, 'requestTopic')
        self.api.register_function(lambda caller: [1, 'stopping', []], 'getPublications')
        self.uri = 'http://127.0.0.1:%d/' % self.api.server_address[1]
        self.master = rosgraph.Master(name)
        for target in (self.api.serve_forever, self._accept):
            threading.Thread(target=target, daemon=True).start()

    def request_topic(self, caller, topic, protocols):
        return [1, 'ready', ['TCPROS', '127.0.0.1', self.tcpros.getsockname()[1]]]

    def _accept(self):
        while True:
            try:
                sock, _ = self.tcpros.accept()
            except OSError:          # stopped
                return
            with self.lock:
                self.made += 1
            threading.Thread(target=self._refuse, args=(sock,), daemon=True).start()

    def _refuse(self, sock):
        """The handshake refused; counted closed once the server closes its end."""
        with sock:
            sock.settimeout(15.0)
            try:
                read_ros_handshake_header(sock, io.BytesIO(), 64 * 1024)
                sock.sendall(encode_ros_handshake_header({'error': 'node shutting down'}))
                gone = sock.recv(1) == b''
            except ROSHandshakeException:       # closed before its header
                gone = True
            except OSError:
                gone = False
        with self.lock:
            self.closed += gone

    def all_closed(self):
        with self.lock:
            return self.made > 0 and self.closed == self.made

    def stop(self):
        self.api.shutdown()
        self.api.server_close()
        self.tcpros.close()


def descriptors(pid):
    return len(os.listdir('/proc/%d/fd' % pid))


def sockets_to(pid, ports):
    """How many of process ``pid``'s sockets are connected to one of ``ports`` on this
    host (IPv4: what the robots listen on)."""
    with open('/proc/%d/net/tcp' % pid) as table:
        inodes = set(row.split()[9] for row in list(table)[1:]
                     if int(row.split()[2].split(':')[1], 16) in ports)
    sockets = set('socket:[%s]' % inode for inode in inodes)
    held = 0
    for fd in os.listdir('/proc/%d/fd' % pid):
        try:
            held += os.readlink('/proc/%d/fd/%s' % (pid, fd)) in sockets
        except OSError:          # closed meanwhile
            pass
    return held


def listed(node):
    """The publishers (XML-RPC URIs) ``node`` lists a connection to on :data:`TOPIC`."""
    uri = rosgraph.Master(rospy.get_name()).lookupNode(node)
    _, _, connections = xmlrpc.client.ServerProxy(uri).getBusInfo(rospy.get_name())
    return set(c[1] for c in connections if c[4] == TOPIC)


def test_a_server_keeps_nothing_of_robots_that_stopped_while_it_connected(ros):
    name = '/server%d' % SERVER
    proc = subprocess.Popen(
        ['rosrun', 'server_select', 'server', '__name:=server%d' % SERVER,
         '_server_id:=%d' % SERVER, '_profile:=fleet'],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    robots = [StoppingRobot('/stopping_robot%d' % i) for i in range(ROBOTS)]
    try:
        assert wait_until(lambda: name in subscribers(TOPIC, rospy.get_name()), 60.0), \
            '%s never subscribed to %s' % (name, TOPIC)
        pid = Fleet.pid(name)
        before = descriptors(pid)
        for robot in robots:
            robot.master.registerPublisher(TOPIC, 'server_select/SortTask', robot.uri)
        # rospy waits 1 s after a refused handshake before it asks whether the robot
        # still publishes, then gives up
        closed = wait_until(lambda: all(r.all_closed() for r in robots), 20.0)
        for robot in robots:
            robot.master.unregisterPublisher(TOPIC, robot.uri)
        # each registration's publisher update lists every robot registered by then, and the
        # server connects again to one it has given up on (in CI: 10-12 connections to the
        # 5, the later ones made after the first were all closed): the server is judged
        # once nothing to them has been listed, open or unclosed for longer than rospy's
        # wait before it gives up
        ports, uris = set(r.tcpros.getsockname()[1] for r in robots), set(r.uri for r in robots)
        quiet = Lasting(QUIET)
        released = wait_until(lambda: quiet.held('clean', all(
            r.all_closed() for r in robots) and not (listed(name) & uris)
            and sockets_to(pid, ports) == 0), 30.0, period=0.2)
        counts = {'robots': ROBOTS,
                  'connections made': sum(r.made for r in robots),
                  'closed by the server': sum(r.closed for r in robots),
                  'still listed': len(listed(name) & uris),
                  'sockets to them held': sockets_to(pid, ports),
                  'descriptors before, after': (before, descriptors(pid))}
        show('robots refusing the handshake as they stop', [counts])
    finally:
        stop_group(proc)
        for robot in robots:
            robot.stop()
    assert all(r.made for r in robots), counts
    assert closed and counts['still listed'] == 0, counts
    assert released, counts
