"""When a probe still out is late (no rospy): TCP's retransmission timeout, per server.

A robot probes a server again when the plan says; if the previous probe of it is still
out then, the new one is not sent. Whether that counts as a failed probe (evidence that
ejects the server) depends on how long this server's answers take: a server on a small CPU
share, busy with a frame, answers in 50-300 ms and is working; one that answered in 10 ms
and has said nothing for 100 ms is hung or cut off. So each server gets the estimate TCP
uses to decide that a segment is lost (RFC 6298, section 2): from each answered probe's
round trip R, ``SRTT`` and ``RTTVAR`` (first ``R`` and ``R/2``; then ``RTTVAR <- 3/4
RTTVAR + 1/4 |SRTT - R|``, ``SRTT <- 7/8 SRTT + 1/8 R``), and a probe still out is *late*
once it is older than ``SRTT + 4 RTTVAR``. A server that has not answered yet has no
estimate: its probe still out is late (it is down until it answers). The probe's own
timeout (``~probe_timeout``) bounds every probe whatever the estimate.

RFC 6298's floor of 1 s and its doubling after a timeout are left out: a probe is checked
only when the next is due (every 0.1-1 s), which is the floor here, and a timed-out probe
ejects its server, whose next answers start the estimate's recovery.
"""

import threading

GAIN = 1.0 / 8.0          # RFC 6298's alpha
VAR_GAIN = 1.0 / 4.0      # beta
K = 4.0                   # deviations a probe may be late by


class AnswerTimes(object):
    """Each server's smoothed probe round trip and its deviation; thread-safe."""

    def __init__(self):
        self._lock = threading.Lock()
        self._servers = {}      # server -> [srtt, rttvar]

    def answered(self, server, rtt):
        """A probe of ``server`` answered after ``rtt`` s."""
        with self._lock:
            estimate = self._servers.get(server)
            if estimate is None:
                self._servers[server] = [rtt, rtt / 2.0]
                return
            srtt, rttvar = estimate
            estimate[1] = (1.0 - VAR_GAIN) * rttvar + VAR_GAIN * abs(srtt - rtt)
            estimate[0] = (1.0 - GAIN) * srtt + GAIN * rtt

    def limit(self, server):
        """Seconds a probe of ``server`` may be out before it is late (None: no answer yet)."""
        with self._lock:
            estimate = self._servers.get(server)
            return None if estimate is None else estimate[0] + K * estimate[1]

    def late(self, server, age):
        """Whether a probe of ``server`` out for ``age`` s is late."""
        limit = self.limit(server)
        return limit is None or age > limit

    def forget(self, server):
        with self._lock:
            self._servers.pop(server, None)
