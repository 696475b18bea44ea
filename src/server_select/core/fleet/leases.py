"""Fleet membership by leases (no rospy): a server is a member from its announcement
until its lease runs out, unless it announces again or says it leaves.

Each server announces itself every ``~announce_period`` s with a lease of a few periods;
the manager keeps the table and publishes the members. A server that stops cleanly says
so (a lease of 0) and leaves at once; one that dies or hangs leaves when its lease ends.
Times are the receiver's (the servers' clocks are not shared).
"""

import threading

LEASE_PERIODS = 3       # a lease lasts this many announcement periods: two may be lost


class Leases(object):
    """The members and when each one's lease ends (thread-safe)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._until = {}       # server -> receiver time its lease ends
        self._holder = {}      # server -> the node that announced it last

    def renew(self, server, node, now, lease):
        """``node`` announced ``server`` at ``now`` for ``lease`` s (0: it leaves).
        Returns ``(changed, other)``: whether the members changed, and the node that held
        ``server``'s lease until now when it is not ``node`` (two nodes claim one id)."""
        if not lease >= 0.0:
            raise ValueError('lease %r s is not a duration' % (lease,))
        with self._lock:
            known = server in self._until
            other = self._holder.get(server) if known else None
            if lease == 0.0:
                if other is not None and other != node:
                    return False, other       # not the holder's own leaving: ignored
                self._until.pop(server, None)
                self._holder.pop(server, None)
                return known, None
            self._until[server] = now + lease
            self._holder[server] = node
            return not known, other if other != node else None

    def expire(self, now):
        """The servers whose lease ended by ``now``, removed (ascending)."""
        with self._lock:
            gone = sorted(s for s, until in self._until.items() if until <= now)
            for server in gone:
                del self._until[server]
                del self._holder[server]
            return gone

    def members(self):
        """The servers holding a lease, ascending."""
        with self._lock:
            return sorted(self._until)
