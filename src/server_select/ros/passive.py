"""A robot's answered tasks as latency samples (``~passive``), published on the manager's
``task_samples`` (the robot turns them into samples:
:meth:`~server_select.core.robot.robot.Robot.on_task_answer`)."""

import itertools

import rospy

from server_select.core.config import names
from server_select.msg import LatencySamples
from server_select.ros.node import fleet
from server_select.ros.seal import SealedPublisher


class TaskSamples(object):
    """Publishes each task sample of robot ``robot_id`` on ``task_samples`` (one
    LatencySamples per answered task)."""

    def __init__(self, robot_id):
        self.robot_id = robot_id
        self.pub = SealedPublisher(fleet(names.TASK_SAMPLES_TOPIC), LatencySamples,
                                   queue_size=100, tcp_nodelay=True)
        self._count = itertools.count(1)

    def publish(self, server, seconds):
        batch = LatencySamples(robot_id=self.robot_id, round=next(self._count),
                               server_id=[server], ok=[True], rtt=[seconds])
        batch.header.stamp = rospy.Time.now()
        self.pub.publish(batch)
