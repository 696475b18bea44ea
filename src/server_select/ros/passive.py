"""A robot's answered tasks as latency samples (``~passive``): its own ranking and the
manager's ``task_samples``."""

import threading

import rospy

from server_select.core.config import names
from server_select.core.selection.passive import TaskBaseline
from server_select.msg import LatencySamples
from server_select.ros.node import fleet
from server_select.ros.seal import SealedPublisher


class TaskSamples(object):
    """Turns answered tasks into samples (:mod:`server_select.core.selection.passive`) for a
    :class:`~server_select.core.selection.candidates.Selection` and publishes each on
    ``task_samples`` (one LatencySamples per answered task).

    A task's round trip enters less its kind's baseline, the least any server's tasks
    take above its probes: the work a task needs on the fastest server when probes measure
    the network only, and the transfer of the task's payload (a probe's is a few bytes)
    when they are load-aware (round trip + the server's expected wait and work). A server
    the robot has not sent tasks to is then compared with its current one on equal terms:
    without the baseline, the server in use carried its payload's transfer in its task
    samples and the others did not, and on near-equal servers the robot moved to the other
    and back."""

    def __init__(self, robot_id, selection):
        self.robot_id, self.selection = robot_id, selection
        self.baseline, self._lock = TaskBaseline(), threading.Lock()
        self.pub = SealedPublisher(fleet(names.TASK_SAMPLES_TOPIC), LatencySamples,
                                   queue_size=100, tcp_nodelay=True)
        self.count = 0

    def on_answer(self, kind, server, rtt):
        """A task of ``kind`` answered by ``server`` after ``rtt`` s (a TaskFlow hook)."""
        with self._lock:
            sample = self.baseline.sample(kind, server, rtt,
                                          self.selection.probe_latency(server))
            if sample is not None:
                self.count += 1
        if sample is None:
            return      # the kind's baseline is still being learned
        self.selection.on_sample(server, True, sample, probe=False)
        batch = LatencySamples(robot_id=self.robot_id, round=self.count, server_id=[server],
                               ok=[True], rtt=[sample])
        batch.header.stamp = rospy.Time.now()
        self.pub.publish(batch)
