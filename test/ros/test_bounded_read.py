"""Inbound bounds on a real socket pair: whatever the sizes, kinds and ids of the
messages in a stream, exactly those within the limit arrive, whole and in order, and
each longer one is refused, unkept; a header over its limit is refused from its length."""

import io
import socket
import struct
import threading

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rosgraph.network import ROSHandshakeException, encode_ros_handshake_header
from rospy.exceptions import TransportTerminated
from rospy.impl.tcpros_base import TCPROSTransport
from rospy.impl.tcpros_pubsub import TCPROSSub

from server_select.core.config.limits import MESSAGE_LIMITS
from server_select.msg import ServerAnnouncement, SortTask
from server_select.ros import bounded_read

TOPIC = '/bounded_test'
LIMIT = 400          # bytes: a SortTask of about 80 values


def wire(msg):
    buffer = io.BytesIO()
    msg.serialize(buffer)
    data = buffer.getvalue()
    return struct.pack('<I', len(data)) + data


def received(stream, chunk, topic=TOPIC, cls=SortTask, limit=LIMIT):
    """The messages a subscriber's transport of ``cls`` on ``topic`` reads from ``stream``
    (bytes), sent in pieces of ``chunk`` bytes (``limit``: the topic's own; None: none)."""
    if limit is not None:
        bounded_read.limit(topic, limit)
    ours, theirs = socket.socketpair()

    def send():
        for start in range(0, len(stream), chunk):
            theirs.sendall(stream[start:start + chunk])
        theirs.shutdown(socket.SHUT_WR)
    writer = threading.Thread(target=send)
    writer.start()
    transport = TCPROSTransport(TCPROSSub(topic, cls), topic)
    transport.socket, transport.header = ours, {'callerid': '/sender'}
    got = []
    try:
        while True:
            got.extend(transport.receive_once())
    except TransportTerminated:
        return got
    finally:
        writer.join()
        ours.close()
        theirs.close()


tasks = st.lists(st.tuples(st.integers(0, 2 ** 32 - 1), st.integers(0, 2 ** 32 - 1),
                           st.integers(0, 200), st.text(max_size=30)), max_size=12)


@settings(max_examples=60, deadline=None)
@given(tasks=tasks, chunk=st.one_of(st.integers(1, 700), st.just(1 << 20)))
def test_exactly_the_messages_within_the_limit_arrive_in_order(tasks, chunk):
    msgs = [SortTask(robot_id=robot, task_id=task, data=list(range(values)))
            for robot, task, values, _ in tasks]
    for msg, (_, _, _, frame) in zip(msgs, tasks):
        msg.header.frame_id = frame
    before = bounded_read.refused()[0].get('/sender on %s' % TOPIC, 0)
    got = received(b''.join(wire(m) for m in msgs), chunk)
    within = [m for m in msgs if len(wire(m)) - 4 <= LIMIT]
    assert [(m.robot_id, m.task_id, tuple(m.data), m.header.frame_id) for m in got] == \
        [(m.robot_id, m.task_id, tuple(m.data), m.header.frame_id) for m in within]
    assert bounded_read.refused()[0].get('/sender on %s' % TOPIC, 0) - before == \
        len(msgs) - len(within)


@settings(max_examples=30, deadline=None)
@given(fields=st.dictionaries(st.sampled_from(['topic', 'type', 'md5sum', 'callerid']),
                              st.text(max_size=50)), padding=st.integers(0, 3000),
       most=st.integers(16, 4000), extra=st.binary(max_size=20))
def test_a_header_is_read_when_within_its_limit_and_refused_unread_when_not(
        fields, padding, most, extra):
    fields = dict(fields, padding='x' * padding)
    encoded = encode_ros_handshake_header(fields)
    ours, theirs = socket.socketpair()
    try:
        theirs.sendall(encoded + extra)
        buffer = io.BytesIO()
        if len(encoded) - 4 > most:
            with pytest.raises(ROSHandshakeException, match='more than %d' % most):
                bounded_read.read_header(ours, buffer, 4096, most)
        else:
            assert bounded_read.read_header(ours, buffer, 4096, most) == fields
            assert buffer.getvalue() == b''       # what follows is left for the transport
            if extra:
                assert ours.recv(len(extra), socket.MSG_WAITALL) == extra
    finally:
        ours.close()
        theirs.close()


def test_a_fleet_message_type_has_its_limit_on_any_topic_without_one():
    """A subscriber of server announcements with no limit of its own: one of 2 MB (its
    probe_uri) is refused from its length, the small ones before and after arrive."""
    topic = '/announcements_test'
    big = ServerAnnouncement(server_id=2, probe_uri='x' * (2 << 20))
    small = [ServerAnnouncement(server_id=1), ServerAnnouncement(server_id=3)]
    before = bounded_read.refused()[1]
    got = received(wire(small[0]) + wire(big) + wire(small[1]), 1 << 16, topic,
                   ServerAnnouncement, limit=None)
    assert [m.server_id for m in got] == [1, 3]
    assert bounded_read.refused()[1] - before == 1
    assert MESSAGE_LIMITS[ServerAnnouncement._type] < len(wire(big))
