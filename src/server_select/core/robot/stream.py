"""One task stream of a :class:`~server_select.core.robot.robot.Robot`: its
:class:`~server_select.core.flow.task_flow.TaskFlow` built from the robot's parameters, and
its pacing (no rospy).

A task is due every ``1/rate`` s from a phase of the stream's own within its first period
(robots started together are not in step); the first waits until the robot is ready and
the transport reaches a server. Between sends the flow is ticked at its next wake (an
attempt's deadline, a hedge, a task's timeout), and a send that ``max_in_flight`` held
back goes as soon as a task ends. A driver calls :meth:`Stream.act` at
:meth:`Stream.next_time` and again after each :meth:`Stream.resolve`.
"""

import functools

from server_select.core.flow import attempts
from server_select.core.flow.task_flow import HEDGE_QUANTILE, TaskFlow


class _Attempts(object):
    """Every attempt told to the robot's count of its sends, to its rule (its moves, its
    own state) and to its health table (where tasks went)."""

    def __init__(self, *observers):
        self.observers = [o for o in observers if o is not None]

    def started(self, server, kind=None, first=True, order=None):
        for observer in self.observers:
            observer.started(server, kind, first, order)

    def ended(self, server, rtt=None):
        for observer in self.observers:
            observer.ended(server, rtt)


class Stream(object):
    """The stream of ``kind`` tasks (see :class:`~server_select.core.robot.robot.Robot`)
    at ``rate`` a second, task ids from ``ids``, at most ``limit`` tasks (0: no limit)."""

    def __init__(self, robot, kind, rate, get, ids, limit=0):
        self.robot, self.kind, self.rate, self.limit = robot, kind, rate, limit
        self.period = 1.0 / rate
        self.random = robot._random('tasks/%s' % kind.kind)
        selection, balancer = robot.selection, robot.balancer
        deadlines = attempts.from_params(get, kind.kind, lambda: self.period,
                                         kind.newest_wins, robot.load)
        self.flow = TaskFlow(
            kind.kind, get('task_timeout'),
            candidates=functools.partial(selection.candidates, kind.kind,
                                         fresh=deadlines.fresh), make=kind.make,
            publish=self._publish, check=kind.check, report=self._report,
            run_local=kind.run_local, on_failure=robot.on_failure,
            on_success=robot.health.task_ok, deadlines=deadlines,
            ids=ids, clock=robot.clock, hedge=HEDGE_QUANTILE if get('hedge') else None,
            budget=robot.budget, max_in_flight=get('max_in_flight'),
            newest_wins=kind.newest_wins, on_busy=functools.partial(robot.on_busy, kind.kind),
            attempts=_Attempts(robot.sends, balancer, robot.health),
            copies=balancer.copies if balancer is not None else 1,
            on_answer=functools.partial(robot.on_task_answer, kind.kind)
            if robot.baseline is not None else None)
        self.started = False
        self.next_send = None
        self._no_input_since = None

    def set_rate(self, rate):
        """``rate`` tasks a second from the next send on (tuned while running)."""
        self.rate, self.period = rate, 1.0 / rate
        if self.next_send is not None:
            self.next_send = min(self.next_send, self.robot.clock() + self.period)

    def start(self, now):
        self.next_send = now + self.period * (1.0 + self.random.random())

    def next_time(self):
        """When :meth:`act` is next due (the clock's time; 0.0: at once; None: not started)."""
        if self.next_send is None:
            return None
        if self.flow.due():
            return 0.0
        wake = self.flow.next_wake()
        return self.next_send if wake is None else min(wake, self.next_send)

    def act(self):
        """Send what is due now and tick the flow."""
        now = self.robot.clock()
        if now >= self.next_send:      # steady: one period on; fallen behind: from now
            self.next_send += self.period
            if self.next_send <= now:
                self.next_send = now + self.period
            self._period_due(now)
        self.flow.tick()
        if self.flow.due():
            self.flow.send_next(self.robot.stamp())

    def _period_due(self, now):
        if self.limit and self.flow.sent >= self.limit:
            return
        if not self.kind.ready():
            # a camera slower than the task rate leaves some ticks without a frame: only
            # a wait of two periods (at least 1 s) is worth a word
            self._no_input_since = self._no_input_since or now
            if now - self._no_input_since > max(1.0, 2.0 * self.period):
                self.robot.events.no_input(self.kind.kind, now - self._no_input_since)
            return
        self._no_input_since = None
        if not self.started:
            waits = self.robot.transport.unready(self.kind.kind) or (
                '' if self.robot.ready() else 'a server')
            if waits:
                self.robot.events.waiting(self.kind.kind, waits)
                return
            self.started = True
            self.robot.events.started(self.kind.kind)
        self.flow.send_next(self.robot.stamp())

    def _publish(self, request, server, budget):
        self.robot.transport.send_task(self.kind.kind, request, server,
                                       budget if self.robot.load is not None else None)

    def _report(self, outcome):
        self.robot.events.report(outcome)

    def resolve(self, task_id, server, ok, error='', result=None, busy=False):
        """An answer for ``task_id`` from ``server``: the flow's
        :class:`~server_select.core.flow.outcome.Resolution`; then ask :meth:`next_time`."""
        return self.flow.resolve(task_id, server, ok, error, result, busy)
