"""A robot's probe rounds (no rospy): which servers its plan says are due, which probes are
still out, and when one is late.

A server whose previous probe is still out is not probed again; once that probe is late
for this server (:class:`~server_select.core.robot.answer_time.AnswerTimes`: twice its
longest recent answer) it gets a failed sample each round instead (:data:`STILL_OUT`): a
link down is known by the next probe, a busy server on a small CPU share is given the time
its answers take. Probes are numbered one series for the robot, rounds another.
"""

import itertools

from server_select.core.robot.answer_time import AnswerTimes

ROUND_FLOOR = 0.001     # two probe rounds at least this far apart (s)


class Probe(object):
    """A probe out: to ``server``, number ``seq``, sent at ``sent`` in round ``round``;
    ``handle``: the transport's, whose ``out_for()`` (if it has one) times it."""
    __slots__ = ('server', 'seq', 'sent', 'round', 'handle', 'done')

    def __init__(self, server, seq, sent, round_number):
        self.server, self.seq, self.sent, self.round = server, seq, sent, round_number
        self.handle, self.done = None, False


class ProbeRounds(object):
    """The rounds of ``plan`` (a :class:`~server_select.core.robot.probe_plan.ProbePlan`).
    Not thread-safe: the robot holds its lock around every call."""

    def __init__(self, plan):
        self.plan = plan
        self.answer_times = AnswerTimes()
        self.answered = set()            # servers that have answered a probe
        self.sent = 0
        self._out = {}                   # server -> its Probe
        self._seq, self._rounds = itertools.count(1), itertools.count(1)
        self._first = self._last = 0.0

    def start(self, servers, now):
        """Probing starts: every server due, the first round one probe period on (as the
        paper's timer had it: servers started with the robot register meanwhile)."""
        for server in servers:
            self.plan.add(server, now)
        self._first = now + self.plan.tick

    def next_time(self):
        due = self.plan.next_time()
        return None if due is None else max(due, self._first, self._last + ROUND_FLOOR)

    def round(self, now, contenders, task_rate):
        """``(round number, [(server, seq, late)])`` of the servers due now (``late``: its
        probe still out is late, a failed sample instead of a call); None: none due."""
        self._last = now
        self.plan.update(contenders, now, task_rate)
        due = [s for s in self.plan.due(now) if not self._still_out(s, now)]
        if not due:
            return None
        number, probes = next(self._rounds), []
        for server in due:
            late, seq = self._still_out(server, None), next(self._seq)
            if not late:
                self._out[server] = Probe(server, seq, now, number)
                self.sent += 1
            probes.append((server, seq, late))
        return number, probes

    def sent_with(self, server, seq, handle):
        probe = self._out.get(server)
        if probe is not None and probe.seq == seq:
            probe.handle = handle

    def _still_out(self, server, now):
        """Whether ``server``'s previous probe is still out (with ``now``: and not late
        yet, by the clock of its round trips where the transport keeps one)."""
        probe = self._out.get(server)
        if probe is None or probe.done:
            return False
        if now is None:
            return True
        out_for = getattr(probe.handle, 'out_for', None)
        out_for = out_for() if out_for is not None else None
        return not self.answer_times.late(server, now - probe.sent if out_for is None
                                          else out_for)

    def end(self, server, seq, rtt=None):
        """Probe ``seq`` of ``server`` ended (``rtt``: answered after that long): the
        Probe, or None when it is not the one out (late, ended already, server gone)."""
        probe = self._out.get(server)
        if probe is None or probe.seq != seq or probe.done:
            return None
        probe.done = True
        if rtt is not None:
            self.answered.add(server)
            self.answer_times.answered(server, rtt)
        return probe

    def add(self, server, now):
        """A new server, due at once; False if it is one already."""
        if server in self.plan.servers:
            return False
        self.plan.add(server, now)
        return True

    def remove(self, server):
        self.plan.remove(server)
        self._out.pop(server, None)
        self.answered.discard(server)
        self.answer_times.forget(server)
