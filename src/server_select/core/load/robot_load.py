"""A load-aware robot's view of its servers' load, fed by its probe answers
(:class:`~server_select.core.load.board.LoadBoard`), and what its probes announce (no
rospy: the node and the simulator hand it :class:`Load` reports and their clock)."""

import threading
import time

from server_select.core.load.demand import SendRate
from server_select.core.load.board import LoadBoard


class RobotLoad(object):
    """What the robot's tasks would wait for at each server: ``mix`` is ``{kind: tasks
    per second}`` of the robot's streams. ``target(kind)`` names the server the robot's
    next ``kind`` task goes to: a probe of it announces the rate the robot sends that kind
    at (``sends``, the robot's :class:`~server_select.core.load.demand.SendRate`, the count
    its rule reads; the kind's rate in ``mix`` until its first task is sent), a probe of
    any other announces none of it, so that servers count the robot's tasks where they go
    now (frames to one server and sort tasks to another, each where it goes). A report older
    than ``max_age`` s (the robot's window: one age for every use of an answer) counts as
    none. Thread-safe."""

    def __init__(self, mix, target=None, balancer=None, clock=time.monotonic, max_age=2.0,
                 sends=None):
        self.board = LoadBoard(mix, max_age=max_age, clock=clock)
        self.balancer = balancer     # a peer's rule hears every answer's load too
        self.mix = dict(mix)
        self.kinds = sorted(mix)
        self.target = target
        self.sends = sends or SendRate(clock)
        self._clock = clock
        self._lock = threading.Lock()      # the mix, tuned while probes read it

    def on_answer(self, server, load, rtt=None):
        """A probe answer of ``server`` reporting ``load`` (a
        :class:`~server_select.core.load.work_queue.Load`) that took ``rtt`` s: its wait
        (s)."""
        self.board.update(server, load, rtt)
        if self.balancer is not None and rtt is not None:
            self.balancer.probed(server, rtt, load)
        return self.board.wait(server)

    def sent(self, server, kind):
        self.board.sent(server, kind)

    def announcement(self, server):
        """``(kinds, tasks per second of each)`` for a probe of ``server``."""
        going = [self.target is not None and self.target(kind) == server
                 for kind in self.kinds]
        if not any(going):
            return self.kinds, [0.0] * len(self.kinds)
        now, sent = self._clock(), set(self.sends.kinds())
        with self._lock:
            return self.kinds, [0.0 if not there else self.sends.count(kind, now) /
                                self.sends.horizon if kind in sent else self.mix[kind]
                                for kind, there in zip(self.kinds, going)]

    def set_rate(self, kind, rate):
        """The robot's ``kind`` stream sends ``rate`` tasks a second from now (tuned)."""
        with self._lock:
            self.mix[kind] = rate
            self.board.set_mix(self.mix)

    def expected(self, kind):
        """``(server) -> seconds``: backlog + work of a ``kind`` task there (None: unknown),
        what an attempt's deadline follows."""
        return lambda server: self.board.expected(server, kind)

    def fresh_for(self, kind, factor, period):
        """``(server) -> seconds``: how long a ``kind`` task (a camera frame, one every
        ``period()`` s, the stream's period as it is now) is worth waiting for at a server: until
        the next frame is due, and at least ``factor`` x (round trip + work) there with no
        queue (None: unknown)."""
        def seconds(server):
            unqueued = self.board.unqueued(server, kind)
            return None if unqueued is None else max(period(), factor * unqueued)
        return seconds

    def forget(self, server):
        self.board.forget(server)
