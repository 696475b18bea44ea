"""A probe's round trip is the kernel's stamps, not when the robot wrote and read: a robot
that reads 150 ms late (busy with its own work, or stalled by its CPU share) still
measures when the answer came, and its request's departure is when it left the stack."""

import socket
import time

from server_select.core.util.procs import wait_until
from server_select.ros.probe_client import STAMP_SPACE, arrival, departures, stamp_packets
from server_select.ros.probe_loop import Flight


def tcp_pair():
    """Two ends of a TCP connection on loopback (the kind a probe uses)."""
    with socket.socket() as listener:
        listener.bind(('127.0.0.1', 0))
        listener.listen(1)
        robot = socket.create_connection(listener.getsockname())
        server, _ = listener.accept()
    return robot, server


def stamping(robot, server):
    """Whether a byte from ``server`` now reaches ``robot`` stamped. The kernel turns
    receive stamps on for the whole stack in a work item of its own after the first
    socket asks (``net_enable_timestamp``), so the first packets after that may come
    unstamped; a probe's answer then counts from when it was read."""
    server.sendall(b'.')
    _, ancillary, _, _ = robot.recvmsg(1, STAMP_SPACE)
    return arrival(ancillary) is not None


def test_the_kernel_stamps_an_answer_when_it_arrives_not_when_it_is_read():
    robot, server = tcp_pair()
    with robot, server:
        assert stamp_packets(robot) == (True, True)
        assert wait_until(lambda: stamping(robot, server), 5.0)
        sent = time.time()
        server.sendall(b'answer')
        time.sleep(0.15)                      # the robot gets round to it late
        read = time.time()
        data, ancillary, _, _ = robot.recvmsg(64, STAMP_SPACE)
        arrived = arrival(ancillary)
    print('\nanswer sent at 0, arrived at %.2f ms by the kernel\'s stamp, read at %.1f ms'
          % (1e3 * (arrived - sent), 1e3 * (read - sent)))
    assert data == b'answer'
    assert sent - 0.001 <= arrived < sent + 0.02 < read


def test_no_stamp_without_the_option():
    robot, server = tcp_pair()
    with robot, server:
        server.sendall(b'x')
        _, ancillary, _, _ = robot.recvmsg(64, STAMP_SPACE)
    assert arrival(ancillary) is None


def test_the_kernel_stamps_a_request_as_it_leaves_and_the_queue_is_emptied():
    robot, server = tcp_pair()
    with robot, server:
        assert stamp_packets(robot) == (True, True)
        before = time.time()
        robot.sendall(b'request')
        after = time.time()
        stamps = departures(robot)
        assert server.recv(64) == b'request'
        assert departures(robot) == []          # read once: nothing left to poll ready
        robot.sendall(b'again')
        second = departures(robot)
    print('\nrequest written within %.1f us, left by the kernel\'s stamp after %.1f us'
          % (1e6 * (after - before), 1e6 * (stamps[-1] - before)))
    assert len(stamps) == 1 and before <= stamps[0] <= after
    assert len(second) == 1 and second[0] >= stamps[0]


def test_a_request_s_own_stamp_is_read_and_the_reading_stops_there():
    robot, server = tcp_pair()
    with robot, server:
        assert stamp_packets(robot) == (True, True)
        robot.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)    # a send, a packet
        robot.sendall(b'old')                   # its stamp left unread
        middle = time.time()
        robot.sendall(b'new')
        robot.sendall(b'newer')
        read = departures(robot, until=middle)
        rest = departures(robot)
    assert len(read) == 2 and read[0] < middle <= read[1]
    assert len(rest) == 1 and rest[0] >= read[1]


def test_no_send_stamp_without_the_option():
    robot, server = tcp_pair()
    with robot, server:
        robot.sendall(b'x')
        assert departures(robot) == []


def test_a_probe_is_out_by_its_send_stamp_and_not_while_its_answer_waits_unread():
    """The still-out rule's clock (``Flight.out_for``): from the request's departure, as
    its round trip is; an answer in the socket that the robot has not read yet is not
    the server's delay."""
    robot, server = tcp_pair()
    with robot, server:
        departed = time.time() - 0.080          # the kernel sent it 80 ms ago
        flight = Flight(None, robot, time.perf_counter(), 0.5, None, sent=departed)
        assert 0.080 <= flight.out_for() < 1.0   # (a loaded host may stall the test)
        assert stamp_packets(robot) == (True, True)
        robot.sendall(b'request')         # its send stamp left on the error queue: polls
        assert server.recv(64) == b'request'            # ready, and is no answer
        assert flight.out_for() >= 0.080
        server.sendall(b'answer')
        assert wait_until(lambda: flight.out_for() == 0.0, 2.0)
        assert Flight(None, None, 0.0, 0.5, None).out_for() is None   # no socket: unknown
