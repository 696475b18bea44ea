"""Links between simulated hosts, as the testbed's emulator and TCP make them (no rospy).

A message from host ``a`` to host ``b`` sent at ``t`` leaves when the link's state at ``t``
lets it (:meth:`Scenario.link`): while the link is down, or for each lost packet, TCP sends
it again after its retransmission timeout (:data:`RTO_MIN`, doubling with each try, as
Linux does), so a message sent into an outage arrives at the first retransmission after
the link is back, not when the link comes back. It then takes the link's one-way delay
(uniform within +- the jitter, as the emulator draws it per packet), its bytes at the
link's rate, and the middleware's own delay per message (``hop``: serialising, the
nodes' threads; measured, :mod:`~server_select.sim.model`).

A :class:`Connection` is one TCP connection (a topic's, robot to server or back): it
delivers in order (a message never overtakes the one before: head-of-line blocking) and
what is written behind a retransmitted message waits for it, as on a connection that
lived through an outage. The robot node makes a task connection anew when the server
answers a probe while the connection retransmits only every second or less often
(``core/util/tcp.py``'s ``stalled``): :meth:`Connection.stalled`, :meth:`Connection.close`
(what it held is lost). A probe goes on a connection of its own (:meth:`Network.once`): a
probe that timed out is dropped with its connection.
"""

import math

from server_select.core.util.tcp import STALLED_RTO

RTO_MIN = 0.2        # s: Linux's least retransmission timeout
RTO_MAX = 120.0
MSS = 1448           # bytes of payload per packet


class Network(object):
    """The scenario's links; ``hop`` s of middleware delay per message."""

    def __init__(self, scenario, streams, hop):
        self.scenario, self.streams, self.hop = scenario, streams, float(hop)

    @staticmethod
    def rto_at(sent, t):
        """The retransmission timeout at ``t`` of a message first sent at ``sent`` and not
        through yet (Linux doubles it from :data:`RTO_MIN` at each try)."""
        rto, due = RTO_MIN, sent + RTO_MIN
        while due <= t and rto < RTO_MAX:
            rto = min(RTO_MAX, 2.0 * rto)
            due += rto
        return rto

    def _departure(self, a, b, t, size, rng):
        """When the message from ``a`` to ``b`` sent at ``t`` gets through (its last
        retransmission), and the link state then; the RTO it ended at."""
        rto = RTO_MIN
        packets = max(1, int(math.ceil(size / float(MSS))))
        for _ in range(64):
            state = self.scenario.link(a, b, t)
            if not state.down and (state.loss <= 0 or
                                   rng.random() >= 1.0 - (1.0 - state.loss) ** packets):
                return t, state, rto
            t += rto
            rto = min(RTO_MAX, 2.0 * rto)
        return t, self.scenario.link(a, b, t), rto

    def transit(self, a, b, t, size, rng):
        """``(arrival time, the RTO the connection is left at)`` of a message."""
        t, state, rto = self._departure(a, b, t, size, rng)
        delay = state.delay
        if state.jitter > 0:
            delay += rng.uniform(-state.jitter, state.jitter)
        seconds = max(0.0, delay) * 1e-3 + self.hop
        if state.rate > 0:
            seconds += size / (state.rate * 1e6)
        return t + seconds, rto

    def once(self, a, b, t, size, tag):
        """The arrival time of one message on a fresh connection (a probe)."""
        return self.transit(a, b, t, size, self.streams.rng('link', a, b, tag))[0]

    def connection(self, a, b, tag):
        return Connection(self, a, b, self.streams.rng('link', a, b, tag))


class Connection(object):
    """One TCP connection from host ``a`` to ``b``: in order, its backoff remembered."""

    def __init__(self, network, a, b, rng):
        self.network, self.a, self.b, self.rng = network, a, b, rng
        self.last_arrival = 0.0
        self.stalled_until = 0.0     # a retransmitted message's arrival: later ones ride it
        self.stalled_since = None    # when that message was first sent
        self.closed = False

    def send(self, t, size):
        """The arrival time of a message sent at ``t``: with a retransmitted message still
        on its way, it goes with that one's retransmission (new data waits behind it)."""
        if t < self.stalled_until:
            return self.stalled_until
        arrival, rto = self.network.transit(self.a, self.b, t, size, self.rng)
        arrival = max(arrival, self.last_arrival)
        if rto > RTO_MIN:
            self.stalled_until, self.stalled_since = arrival, t
        self.last_arrival = arrival
        return arrival

    def stalled(self, t):
        """Whether at ``t`` the connection holds data retransmitted only every
        ``STALLED_RTO`` s or less often."""
        return self.stalled_until > t and \
            Network.rto_at(self.stalled_since, t) >= STALLED_RTO

    def close(self):
        """Closed with a reset: what it still holds never arrives."""
        self.closed = True
