"""What the kernel says about a TCP connection's retransmissions (no rospy).

After a link outage, a TCP connection that had data in flight when the link went down
retransmits it with a timeout that doubled at each try (RFC 6298; 0.2 s, then 0.4, 0.8,
... up to 120 s on Linux): after a 15 s outage its next try may be 10 s away, and every
message written meanwhile waits behind it, while a new connection would carry one at once.
:func:`stalled` tells such a connection from one that lost a packet or two: data
unacknowledged and the kernel's retransmission timeout, with its back-off, at a second
or more (a timeout of a link that works is the round trip + 0.2 s; one lost packet
doubles it once).
"""

import collections
import socket
import struct

# struct tcp_info (linux/tcp.h) begins: u8 state, ca_state, retransmits, probes, backoff,
# options, wscale, flags; u32 rto (us), ato, snd_mss, rcv_mss, unacked
_HEAD = struct.Struct('=8B5I')
STALLED_RTO = 1.0        # s: a retransmission timeout this long has backed off at least twice

Retransmission = collections.namedtuple('Retransmission', 'unacked rto backoff')


def parse(info):
    """The :class:`Retransmission` state in the bytes of a ``TCP_INFO`` (None when short):
    segments unacknowledged, the retransmission timeout (s, backed off) and how many times
    it was doubled."""
    if len(info) < _HEAD.size:
        return None
    fields = _HEAD.unpack_from(info)
    return Retransmission(unacked=fields[12], rto=fields[8] / 1e6, backoff=fields[4])


def retransmission(sock):
    """:func:`parse` of ``sock``'s ``TCP_INFO``; None where it cannot be read (not a TCP
    socket, closed, or a system without it)."""
    option = getattr(socket, 'TCP_INFO', None)
    if option is None or sock is None:
        return None
    try:
        return parse(sock.getsockopt(socket.IPPROTO_TCP, option, _HEAD.size))
    except (OSError, ValueError):
        return None


def stalled(sock, rto=STALLED_RTO):
    """Whether ``sock`` holds data the kernel retransmits only every ``rto`` s or less
    often (a connection that lived through an outage with data in flight)."""
    state = retransmission(sock)
    return state is not None and state.unacked > 0 and state.rto >= rto


def reset_on_close(sock):
    """Make ``sock``'s close send a reset at once, dropping what it still holds (a stalled
    connection's peer would otherwise see it open until its data got through, and a ROS
    subscriber does not connect again to a publisher it believes it is connected to)."""
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack('ii', 1, 0))
    except (OSError, AttributeError):
        pass
