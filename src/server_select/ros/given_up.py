"""A subscriber's connection that rospy gives up on is closed and dropped from its topic.

rospy connects a subscriber to each publisher from a thread of its own
(``tcpros_pubsub.robust_connect_subscriber``). When the publisher refuses the handshake
(a node that is stopping answers "node shutting down"), rospy's ``connect`` raises with
the new socket still open; the thread waits, finds that the publisher has gone, and ends
without closing it, and the connection stays in its topic's list for good. A server then
kept one socket (in CLOSE-WAIT) and one connection for each robot that stopped while the
server was connecting to it: about 1 stop in 8 here, for as long as robots came and went.
Here a connection whose thread ends without having closed it is closed, which drops it
from its topic (rospy's ``close`` skips a connection already marked done).
"""

from rospy.impl import tcpros_pubsub

_ORIGINAL = {}


def install():
    """Close every subscriber connection rospy gives up on, from now on (idempotent)."""
    if not _ORIGINAL:
        _ORIGINAL['connect'] = tcpros_pubsub.robust_connect_subscriber
        tcpros_pubsub.robust_connect_subscriber = _connect_subscriber


def _connect_subscriber(conn, *args):
    """rospy's, then ``conn`` closed if rospy left it open (its ``close`` clears its
    protocol: one still set was never closed)."""
    try:
        _ORIGINAL['connect'](conn, *args)
    finally:
        if conn.protocol is not None:
            conn.done = False
            conn.close()
