"""Inbound TCPROS handshakes off the accept thread, each with a deadline.

rospy accepts every topic and service connection of a node on one thread and reads the
new connection's handshake header there, with no deadline: one peer that connects and
sends nothing holds every later connection to the node (probes, a robot joining, a robot
reconnecting after an outage) until its TCP gives up. Here the accept thread hands each
new connection to a thread of its own, which has :data:`DEADLINE` s to read the header
(bounded by :mod:`~server_select.ros.bounded_read`); one that does not finish in time is
closed, with a throttled line naming the peer. At most :data:`MOST_AT_ONCE` handshakes
are under way at once; a connection beyond them is closed at once (it may try again).
A header rospy refuses (no such topic or service here, a wrong type) is answered with
rospy's error and closed with a throttled line, the peer's words cut: rospy's own line
echoed the whole header, unthrottled (a 900 KB callerid made each line 900 KB). After the
header the connection is rospy's, as before.
"""

import io
import socket
import threading

import rospy
from rosgraph.network import ROSHandshakeException
from rospy.impl import tcpros_base

from server_select.core.trust.senders import Throttle
from server_select.core.util.bounded import PEER_CHARS, peer
from server_select.ros import bounded_read

DEADLINE = 2.0           # s a new connection has to send its header
MOST_AT_ONCE = 64        # handshakes under way at once

_SLOTS = threading.BoundedSemaphore(MOST_AT_ONCE)
_THROTTLE = Throttle(5.0)
_ORIGINAL = {}


def install():
    """Handshakes off the accept thread from now on (before the node starts; idempotent)."""
    if _ORIGINAL:
        return
    bounded_read.install()       # the header read below is the bounded one
    _ORIGINAL['read_header'] = tcpros_base.read_ros_handshake_header
    tcpros_base.TCPROSServer._tcp_server_callback = _accepted


def _accepted(server, sock, client_addr):
    """The accept thread's part: a thread for the handshake, or the connection closed."""
    if not _SLOTS.acquire(blocking=False):
        _close(sock, client_addr, 'more than %d handshakes under way' % MOST_AT_ONCE)
        return
    try:
        threading.Thread(target=_handshake, args=(server, sock, client_addr),
                         name='handshake', daemon=True).start()
    except RuntimeError:         # no thread to be had: the node is stopping, or starved
        _SLOTS.release()
        _close(sock, client_addr, 'no thread for its handshake')


def _handshake(server, sock, client_addr):
    try:
        sock.settimeout(DEADLINE)
        try:
            header = _ORIGINAL['read_header'](sock, io.BytesIO(), 4096)
        except socket.timeout:
            _close(sock, client_addr, 'no handshake within %g s' % DEADLINE)
            return
        except (ROSHandshakeException, OSError) as error:
            # rospy's own words for a connection that failed before its header (a client
            # that gave up, or looked only: ros/node.py's filter keeps that one quiet)
            _close(sock)
            if not rospy.core.is_shutdown_requested():
                rospy.logwarn('Inbound TCP/IP connection failed: %s', error)
            return
        sock.settimeout(None)
        _connect(server, sock, client_addr, header)
    finally:
        _SLOTS.release()


def _connect(server, sock, client_addr, header):
    """rospy's callback after the header: the connection to its topic or service, or
    refused with rospy's error (a throttled line, the peer's words cut)."""
    try:
        if 'topic' in header:
            error = server.topic_connection_handler(sock, client_addr, header)
        elif 'service' in header:
            error = server.service_connection_handler(sock, client_addr, header)
        else:
            error = 'no topic or service name detected'
        if error:
            stopping = rospy.core.is_shutdown_requested()
            tcpros_base.write_ros_handshake_header(
                sock, {'error': 'node shutting down' if stopping else error})
            _close(sock, client_addr, None if stopping else '%s\'s header: %s' % (
                peer(header.get('callerid', 'a node without a callerid')), error))
    except Exception as error:       # rospy's handlers raise what the peer's header caused
        _close(sock, client_addr, None if rospy.core.is_shutdown_requested() else
               'its connection failed: %s' % error)


def _close(sock, client_addr=None, why=None):
    """Close ``sock``; with ``why``, say so in a throttled line naming the peer."""
    try:
        sock.close()
    except OSError:
        pass
    if why is not None:
        say_closed(_THROTTLE, 'a connection', client_addr, why)


def say_closed(throttle, what, client_addr, why):
    """A line, at most one a ``throttle`` period, that ``what`` from ``client_addr`` was
    closed for ``why``, naming the peer (cut) and how many such lines were held back."""
    due, held = throttle.due()
    if due:
        address = '%s:%s' % tuple(client_addr[:2]) if client_addr else 'an unknown peer'
        rospy.logwarn('%s: closed %s from %s: %s%s' % (
            rospy.get_name(), what, peer(address), peer(why, 2 * PEER_CHARS),
            '; %d more before' % held if held else ''))
