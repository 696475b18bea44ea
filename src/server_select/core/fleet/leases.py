"""Fleet membership by leases (no rospy): a server is a member from its announcement
until its lease runs out, unless it announces again or says it leaves; its id is bound to
the node that announced it meanwhile.

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
        Returns ``(changed, holder)``: whether the members changed, and the node that holds
        ``server`` when that is not ``node``: an id is one node's from its first
        announcement until it leaves or its lease ends, and another node's claim meanwhile
        is refused (changes nothing)."""
        if not lease >= 0.0:
            raise ValueError('lease %r s is not a duration' % (lease,))
        with self._lock:
            holder = self._holder.get(server)
            if holder not in (None, node) and self._until[server] > now:
                return False, holder      # (once its lease ended, ``node`` may take the id)
            known = server in self._until
            if lease == 0.0:
                self._until.pop(server, None)
                self._holder.pop(server, None)
                return known, None
            self._until[server] = now + lease
            self._holder[server] = node
            return not known, None

    def holder(self, server, now=None):
        """The node ``server`` is bound to (None: no lease is held, or, given ``now``, none
        lasts then)."""
        with self._lock:
            if now is not None and self._until.get(server, now) <= now:
                return None
            return self._holder.get(server)

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
