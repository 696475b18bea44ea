"""When a probe still out is late (no rospy): its request not delivered for longer than
twice the server's longest recent answer, and than that answer and a delayed acknowledgement.

A robot probes a server again when its plan says; if the previous probe of it is still out
then, no second one goes. Whether the one still out is a failed probe (evidence that ejects
the server at once) depends on where it is. A link that goes down or a host that stops
answers nothing after answering in 10 ms: the robot should know by its next probe (0.1 s
for a contender), not after ``~probe_timeout``. A server on a small CPU share, busy with a
frame, answers in 5-330 ms as its worker computes or not, and is working: counted as
failed, such probes ejected a server from every robot on it at once, and robots went from
server to server together (2x overload: all six robots ejected the fastest server within
0.6 s of their first frames, then the next, then the last).

So a probe still out is *late* once its request has gone unacknowledged for longer than
:data:`FACTOR` x the longest round trip among the server's last :data:`KEEP` answers, and
than that round trip plus :data:`DELAYED_ACK` (a receiver that has nothing to send yet
acknowledges after 40 ms and a scheduler tick: measured 42-44 ms here): a link that
answered in 10-25 ms is late after 75 ms, by the next probe. The
robot gives its age from the kernel's send stamp, gives none while the answer waits unread,
and none once the server's host has acknowledged every byte of the request (``SIOCOUTQ``):
then the link is up and the server has the request, and whether it answers in time is
for the probe's own timeout to say. A server
that has not answered yet has no history: its probe still out is late (it is down until
it answers). Tried before: no lateness at all, only the probe's timeout (link_flap 1.49x
the oracle: a link down known 0.5 s late); TCP's retransmission timeout (SRTT + 4 RTTVAR,
RFC 6298), whose averages fell to about 20 ms after a few quick answers of a capped
server; twice the longest answer alone, which a server's idle answers set before its first
task made it slow.
"""

import collections
import threading

FACTOR = 2.0     # a probe later than twice the longest recent answer is late
DELAYED_ACK = 0.05   # s: a receiver's delayed acknowledgement (Linux: 40 ms + a tick)
KEEP = 64        # answers per server remembered (6.4 s of a contender's, at 10 Hz)


class AnswerTimes(object):
    """Each server's recent probe round trips; thread-safe."""

    def __init__(self):
        self._lock = threading.Lock()
        self._servers = {}      # server -> deque of its last KEEP round trips

    def answered(self, server, rtt):
        """A probe of ``server`` answered after ``rtt`` s."""
        with self._lock:
            times = self._servers.get(server)
            if times is None:
                times = self._servers[server] = collections.deque(maxlen=KEEP)
            times.append(rtt)

    def limit(self, server):
        """Seconds a probe of ``server`` may go unacknowledged before it is late (None: no
        answer yet)."""
        with self._lock:
            times = self._servers.get(server)
            longest = max(times) if times else None
        return None if longest is None else max(FACTOR * longest, longest + DELAYED_ACK)

    def late(self, server, age):
        """Whether a probe of ``server`` out for ``age`` s is late."""
        limit = self.limit(server)
        return limit is None or age > limit

    def forget(self, server):
        with self._lock:
            self._servers.pop(server, None)
