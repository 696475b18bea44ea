"""``given_up``: a subscriber's connection to a publisher that refuses its handshake (a node
that is stopping answers "node shutting down") and then is gone is closed and dropped
from its topic. rospy alone leaves its socket open (CLOSE-WAIT once the publisher ends)
and the connection listed, for good. A publisher here is a socket that answers the
handshake with that error and waits; no master is needed."""

import io
import socket
import threading

import pytest
import rospy
from rosgraph.network import encode_ros_handshake_header, read_ros_handshake_header
from rospy.impl import tcpros_base, tcpros_pubsub
from rospy.impl.tcpros_base import TCPROSTransport
from std_msgs.msg import String

from server_select.ros import given_up

GONE_URI = 'http://127.0.0.1:1/'     # its XML-RPC does not answer: no longer a publisher


class StoppingPublisher(object):
    """A TCPROS listener that answers every handshake with rospy's "node shutting down"
    error, then waits for the subscriber to close its end (``closed``: set when it did)."""

    def __init__(self):
        self.listener = socket.create_server(('127.0.0.1', 0))
        self.port = self.listener.getsockname()[1]
        self.closed = threading.Event()
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self):
        sock, _ = self.listener.accept()
        with sock:
            read_ros_handshake_header(sock, io.BytesIO(), 4096)
            sock.sendall(encode_ros_handshake_header({'error': 'node shutting down'}))
            sock.settimeout(10.0)
            try:
                if sock.recv(1) == b'':
                    self.closed.set()
            except OSError:
                pass


@pytest.fixture
def subscriber(monkeypatch):
    # what rospy's connect asks the master (none here) first: TCP keep-alive, as by default
    monkeypatch.setattr(tcpros_base, '_use_tcp_keepalive', True)
    sub = rospy.Subscriber('/given_up_topic', String, lambda msg: None)
    yield sub
    sub.unregister()


def connect_once(sub, publisher):
    """One subscriber connection to ``publisher`` as rospy makes it (its thread's body)."""
    conn = TCPROSTransport(tcpros_pubsub.TCPROSSub(sub.resolved_name, String), sub.resolved_name)
    conn.set_endpoint_id(GONE_URI)
    assert sub.impl.add_connection(conn)
    tcpros_pubsub.robust_connect_subscriber(conn, '127.0.0.1', publisher.port, GONE_URI,
                                            sub.impl.receive_callback, sub.resolved_name)
    return conn


def test_a_connection_given_up_on_is_closed_and_dropped(subscriber):
    given_up.install()
    publisher = StoppingPublisher()
    conn = connect_once(subscriber, publisher)
    assert publisher.closed.wait(5.0), 'the subscriber kept its end open'
    assert conn.socket is None and conn.done
    assert conn not in subscriber.impl.connections


def test_rospy_alone_keeps_it(subscriber, monkeypatch):
    """For contrast (why the module exists): rospy's own thread leaves both behind."""
    given_up.install()
    monkeypatch.setattr(tcpros_pubsub, 'robust_connect_subscriber',
                        given_up._ORIGINAL['connect'])
    publisher = StoppingPublisher()
    conn = connect_once(subscriber, publisher)
    try:
        assert not publisher.closed.wait(1.5)
        assert conn.socket is not None and conn in subscriber.impl.connections
    finally:
        conn.done = False
        conn.close()
