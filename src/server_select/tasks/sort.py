"""Sorting int32 arrays, the first paper's task, as a task type (built in: ``~sort_tasks``).

Robot side: ``size`` random values per task (``~task_size``), from a generator seeded with
``seed`` (``~seed``, default the robot id), checked on return (length, sum, order). Server
side: arrays longer than ``max_len`` (``~max_task_len``) are refused.
"""

import random

from server_select.core.config import names
from server_select.core.flow.sort_kernel import check_sorted, fingerprint, make_values, sort_values
from server_select.msg import SortResult, SortTask
from server_select.ros.plugins import MESSAGE_SLACK, TaskPlugin


class Sort(TaskPlugin):
    """An array of int32 values to sort."""

    kind = 'sort'
    task_topic, task_type = names.SORT_TASK_TOPIC, SortTask
    result_topic, result_type = names.SORT_RESULT_TOPIC, SortResult

    def __init__(self, robot_id, settings):
        super(Sort, self).__init__(robot_id, settings)
        self.size = int(settings.get('size', 1000))
        self.max_len = int(settings.get('max_len', 100000))
        self.rng = random.Random(settings.get('seed', robot_id))

    def make(self, task_id, stamp):
        values = make_values(self.rng, self.size)
        task = SortTask(robot_id=self.robot_id, task_id=task_id, data=values)
        task.header.stamp = stamp
        return task, fingerprint(values)

    def check(self, result, context):
        return check_sorted(result.data, context)

    def run_local(self, _task_id, _stamp):
        values = make_values(self.rng, self.size)
        return check_sorted(sort_values(values, len(values)), fingerprint(values))

    def handle(self, task, result):
        result.data = sort_values(task.data, self.max_len)     # TaskError is a ValueError

    rehearse = handle     # (it acts on its result alone)

    def max_bytes(self):
        return 4 * self.max_len + MESSAGE_SLACK
