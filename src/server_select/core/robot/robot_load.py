"""A load-aware robot's view of its servers' load (no rospy): what its attempt deadlines,
fresh frames and samples read of the rule's estimates
(:mod:`~server_select.core.rule.estimates`, the robot's one load model), and what its
probes announce. The node and the simulator hand it :class:`Load` reports and their clock."""

import functools
import threading
import time

from server_select.core.rule.balancer import Balancer
from server_select.core.rule.estimates import SendRate


class RobotLoad(object):
    """What the robot's tasks would wait for at each server: ``mix`` is ``{kind: tasks
    per second}`` of the robot's streams. ``target(kind)`` names the server the robot's
    next ``kind`` task goes to: a probe of it announces the rate the robot sends that kind
    at (``sends``, the robot's :class:`~server_select.core.rule.estimates.SendRate`, the count
    its rule reads; the kind's rate in ``mix`` until its first task is sent), a probe of
    any other announces none of it, so that servers count the robot's tasks where they go
    now (frames to one server and sort tasks to another, each where it goes). What it
    expects of a server is the estimate of ``balancer``, the robot's rule (answers of its
    last ``window`` s); a robot whose ranking chooses, with no rule per task, keeps a
    rule's estimates all the same (told of no attempt, they count its own tasks in flight
    among the others'). Thread-safe."""

    def __init__(self, mix, target=None, balancer=None, clock=time.monotonic, window=2.0,
                 sends=None):
        _check_mix(mix)
        self.sends = sends or SendRate(clock)
        self.balancer = balancer if balancer is not None else \
            Balancer(clock=clock, sends=self.sends, window=window)
        self.mix = dict(mix)
        self.kinds = sorted(mix)
        self.target = target
        self._clock = clock
        self._lock = threading.Lock()      # the mix, tuned while probes read it

    def on_answer(self, server, load, rtt=None):
        """A probe answer of ``server`` reporting ``load`` (a
        :class:`~server_select.core.load.work_queue.Load`) that took ``rtt`` s: its wait
        (s): the answer's wait + work for the robot's mix of kinds there, what a
        load-aware ranking of samples adds to the round trip (None: no answer)."""
        if rtt is not None:
            self.balancer.probed(server, rtt, load)
        with self._lock:
            total = float(sum(self.mix.values()))
            weights = [(kind, rate / total) for kind, rate in sorted(self.mix.items())]
        wait = 0.0
        for kind, weight in weights:
            seconds = self.balancer.answer_wait(server, kind)
            if seconds is None:
                return None
            wait += weight * seconds
        return wait

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
            _check_mix(dict(self.mix, **{kind: rate}))
            self.mix[kind] = rate

    def expected(self, kind):
        """``(server) -> seconds``: what one attempt of a ``kind`` task takes there
        (:meth:`Balancer.attempt_seconds`), what an attempt's deadline follows."""
        return functools.partial(self.balancer.attempt_seconds, kind)

    def fresh_for(self, kind, factor, period):
        """``(server) -> seconds``: how long a ``kind`` task (a camera frame, one every
        ``period()`` s, the stream's period as it is now) is worth waiting for at a server
        (:meth:`Balancer.fresh_seconds`)."""
        return functools.partial(self.balancer.fresh_seconds, kind, factor, period)


def _check_mix(mix):
    """ValueError unless ``mix`` gives a positive rate to some kind (its weights divide by
    the total)."""
    if not mix or not sum(mix.values()) > 0:
        raise ValueError('mix must give a positive weight to some kind, got %r' % (mix,))
