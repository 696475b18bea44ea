"""When a probe still out is late (no rospy): twice the longest of the server's recent answers.

A robot probes a server again when its plan says; if the previous probe of it is still out
then, no second one goes. Whether the one still out is a failed probe (evidence that ejects
the server at once) depends on how long this server's answers take. A link that goes down
or a host that hangs answers nothing after answering in 10 ms: the robot should know by its
next probe (0.1 s for a contender), not after ``~probe_timeout``. A server on a small CPU
share, busy with a frame, answers in 5-330 ms as its worker computes or not, and is
working: counted as failed at 0.1 s, such probes ejected the capped servers of a 2x
overload 39 times a run.

So a probe still out is *late* once older than :data:`FACTOR` x the longest round trip among
the server's last :data:`KEEP` answers (its age by the clock of the round trips: the robot
gives it from the kernel's send stamp, and gives none while the answer waits unread, so a
busy robot's own delay is not counted): a server that answered in 10-25 ms is late after
50 ms, one that has taken up to 330 ms is not late before 0.66 s (its probe's own timeout
comes first). A server that has not answered yet has no history: its probe still out is
late (it is down until it answers). Tried first, and measured too low: TCP's retransmission
timeout (SRTT + 4 RTTVAR, RFC 6298), whose moving averages fell to about 20 ms after a few
quick answers of the capped server and ejected it as often as before.
"""

import collections
import threading

FACTOR = 2.0     # a probe later than twice the longest recent answer is late
# the error of a probe not sent because the last one is still out, and late
STILL_OUT = 'previous probe still in progress'
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
        """Seconds a probe of ``server`` may be out before it is late (None: no answer yet)."""
        with self._lock:
            times = self._servers.get(server)
            return FACTOR * max(times) if times else None

    def late(self, server, age):
        """Whether a probe of ``server`` out for ``age`` s is late."""
        limit = self.limit(server)
        return limit is None or age > limit

    def forget(self, server):
        with self._lock:
            self._servers.pop(server, None)
