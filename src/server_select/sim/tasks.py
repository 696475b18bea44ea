"""What a simulated robot's tasks are (no rospy): a stream as a scenario asks for it
(:class:`Kind`), what travels (:class:`Task`), and a kind as the robot's
:class:`~server_select.core.robot.stream.Stream` takes it, its work drawn from the model
(:class:`TaskKind`)."""

import collections

PROBE_BYTES = 120          # a LatencyProbe request or answer

Kind = collections.namedtuple('Kind', 'name rate newest_wins bytes size')
Kind.__doc__ = """A task stream: kind, tasks per second, whether the newest wins (frames),
bytes of a task and of its result, values per task (sort)."""
Task = collections.namedtuple('Task', 'robot task_id kind work bytes alone')
Task.__doc__ = """A task as it travels: its ``work`` (CPU s where it runs) and the part of it
its content takes (``alone``: what a rerun of it takes before the host's share)."""


class TaskKind(object):
    """A :class:`Kind` as the robot's stream takes it: tasks whose work the model draws."""
    run_local, input = None, 'the simulation'

    def __init__(self, kind, robot_id, model, rng):
        self.kind, self.newest_wins, self._spec = kind.name, kind.newest_wins, kind
        self._robot_id, self._model, self._rng = robot_id, model, rng

    def make(self, task_id, stamp):
        alone = self._model.alone(self.kind, self._rng, self._spec.size)
        work = alone + self._model.shared_delay(self._rng)
        return Task(self._robot_id, task_id, self.kind, work, self._spec.bytes, alone), None

    def check(self, result, context):
        return None

    def ready(self):
        return True
