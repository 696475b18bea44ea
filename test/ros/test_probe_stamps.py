"""A probe answer's arrival is the kernel's stamp, not when the robot read it: a robot
that reads 150 ms late (busy with its own work, or stalled by its CPU share) still
measures when the answer came."""

import socket
import time

from server_select.ros.probe_client import arrival, stamp_arrivals


def tcp_pair():
    """Two ends of a TCP connection on loopback (the kind a probe uses)."""
    with socket.socket() as listener:
        listener.bind(('127.0.0.1', 0))
        listener.listen(1)
        robot = socket.create_connection(listener.getsockname())
        server, _ = listener.accept()
    return robot, server


def test_the_kernel_stamps_an_answer_when_it_arrives_not_when_it_is_read():
    robot, server = tcp_pair()
    with robot, server:
        assert stamp_arrivals(robot)
        sent = time.time()
        server.sendall(b'answer')
        time.sleep(0.15)                      # the robot gets round to it late
        read = time.time()
        data, ancillary, _, _ = robot.recvmsg(64, socket.CMSG_SPACE(16))
        arrived = arrival(ancillary)
    print('\nanswer sent at 0, arrived at %.2f ms by the kernel\'s stamp, read at %.1f ms'
          % (1e3 * (arrived - sent), 1e3 * (read - sent)))
    assert data == b'answer'
    assert sent - 0.001 <= arrived < sent + 0.02 < read


def test_no_stamp_without_the_option():
    robot, server = tcp_pair()
    with robot, server:
        server.sendall(b'x')
        _, ancillary, _, _ = robot.recvmsg(64, socket.CMSG_SPACE(16))
    assert arrival(ancillary) is None
