"""A simulated robot's task stream (no rospy): a :class:`TaskFlow` built from the robot's
parameters as the node builds it, paced as the node's TaskStream paces it (a task every
period once a server is usable, the flow ticked at its next wake, a held-back send made
as soon as a task ends)."""

import collections
import functools

from server_select.core.flow import attempts
from server_select.core.flow.task_flow import ENDED, HEDGE_QUANTILE, TaskFlow
from server_select.sim.events import Wakeup

Kind = collections.namedtuple('Kind', 'name rate newest_wins bytes size')
Kind.__doc__ = """A task stream: kind, tasks per second, whether the newest wins (frames),
bytes of a task and of its result, values per task (sort)."""
Task = collections.namedtuple('Task', 'robot task_id kind work bytes')


class TaskStream(object):
    """One task stream of a robot: a :class:`TaskFlow` paced as the node's TaskStream."""

    def __init__(self, robot, kind, get, ids):
        self.robot, self.kind = robot, kind
        self.loop = robot.loop
        self.period = 1.0 / kind.rate
        selection = robot.selection
        self.rng = robot.sim.streams.rng('tasks', robot.scenario_id, kind.name)
        self.flow = TaskFlow(
            kind.name, get('task_timeout'),
            candidates=functools.partial(selection.candidates, kind.name), make=self._make,
            publish=self._publish, check=lambda result, context: None, report=self._report,
            on_failure=robot.on_failure, on_success=robot.health.task_ok,
            deadlines=attempts.from_params(get, kind.name, kind.rate, kind.newest_wins,
                                           robot.load),
            ids=ids, clock=self.loop.now, hedge=HEDGE_QUANTILE if get('hedge') else None,
            budget=robot.budget, max_in_flight=get('max_in_flight'),
            newest_wins=kind.newest_wins, on_busy=functools.partial(robot.on_busy, kind.name),
            attempts=robot.balancer,
            copies=robot.balancer.copies if robot.balancer is not None else 1)
        self.wake = Wakeup(self.loop, self._act)
        self.started = False
        self.next_send = None

    def start(self, now):
        # robots started together are not in phase: each stream's first task at a
        # phase of its own within its first period
        self.next_send = now + self.period * (1.0 + self.rng.random())
        self.wake.request(self.next_send)

    def _make(self, task_id, stamp):
        work = self.robot.sim.model.work(self.kind.name, self.rng, self.kind.size)
        return Task(self.robot.id, task_id, self.kind.name, work, self.kind.bytes), None

    def _publish(self, task, server, budget):
        # the node gives a task its budget (the server's deadline) when load-aware only
        if self.robot.load is not None:
            self.robot.load.sent(server, self.kind.name)
        self.robot.send(task, server, budget if self.robot.load is not None else 0.0, self)

    def _report(self, outcome):
        self.robot.sim.report(self.robot.id, outcome)

    def resolve(self, task, server, ok, error, busy):
        resolution = self.flow.resolve(task.task_id, server, ok, error, None, busy)
        if ok:
            self.robot.sim.work_answered(self.robot.id, resolution.status == ENDED)
        self._schedule()

    def _act(self):
        now = self.loop.now()
        if now >= self.next_send:
            self.next_send += self.period
            if self.next_send <= now:
                self.next_send = now + self.period
            if self.started or self.robot.ready():
                self.started = True
                self.flow.send_next(now)
        self.flow.tick()
        if self.flow.due():
            self.flow.send_next(now)
        self._schedule()

    def _schedule(self):
        if self.flow.due():
            self.wake.request(self.loop.now())
            return
        wake = self.flow.next_wake()
        self.wake.request(self.next_send if wake is None else min(wake, self.next_send))
