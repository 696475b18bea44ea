"""Compute server: answers latency probes and the sort tasks addressed to it."""

import threading
import time

import numpy as np
import rospy
from rospy.numpy_msg import numpy_msg

from server_select import names
from server_select.msg import SortResult, SortTask
from server_select.node_util import get_param, run
from server_select.params import parse_id, parse_positive
from server_select.sort_task import TaskError, sort_values
from server_select.srv import LatencyProbe, LatencyProbeResponse

EMPTY = np.empty(0, dtype=np.int32)


class ServerNode(object):
    """A compute server of the fleet.

    Tasks are broadcast on ``data`` to every server; each task names the server the robot
    selected when it sent it, and only that server processes it. Deciding by the id
    stamped in the task (rather than by the latest flag each server happens to have seen)
    is what keeps one task from being answered twice, or not at all, around a switch.

    :ROS Parameters:
        - ``~server_id`` (int, required): this server's id.
        - ``~max_task_len`` (int, 1000000): larger sort tasks get an error result.
        - ``~queue_size`` (int, 100): task subscriber queue.
    :ROS Services:
        - ``latency_S<server_id>`` (server_select/LatencyProbe): echo for RTT probing.
    :ROS Subscribers:
        - ``data`` (server_select/SortTask)
    :ROS Publishers:
        - ``processed_data`` (server_select/SortResult): one result per task addressed here.
    """

    def __init__(self):
        self.server_id = parse_id('~server_id', get_param('~server_id'))
        self.max_task_len = parse_positive(
            '~max_task_len', get_param('~max_task_len', 1000000), integer=True)
        queue_size = parse_positive('~queue_size', get_param('~queue_size', 100), integer=True)
        self._lock = threading.Lock()
        self.tasks_done = 0
        self.tasks_failed = 0

        self.result_pub = rospy.Publisher(
            names.SORT_RESULT_TOPIC, numpy_msg(SortResult), queue_size=queue_size)
        self.task_sub = rospy.Subscriber(
            names.SORT_TASK_TOPIC, numpy_msg(SortTask), self.on_sort_task,
            queue_size=queue_size, tcp_nodelay=True, buff_size=1 << 24)
        # Advertised last: a robot that can probe us finds our task topics wired already.
        self.probe_srv = rospy.Service(
            names.probe_service(self.server_id), LatencyProbe, self.on_probe)
        rospy.loginfo('server %d: probe service %s, tasks on %s',
                      self.server_id, self.probe_srv.resolved_name, self.task_sub.resolved_name)
        rospy.on_shutdown(self.on_shutdown)

    def on_probe(self, req):
        return LatencyProbeResponse(
            server_id=self.server_id, seq=req.seq, stamp=req.stamp, server_stamp=rospy.Time.now())

    def on_sort_task(self, task):
        if task.server_id != self.server_id:
            return
        result = SortResult(header=task.header, robot_id=task.robot_id, task_id=task.task_id,
                            server_id=self.server_id)
        start = time.perf_counter()
        try:
            result.data = sort_values(task.data, self.max_task_len)
            result.ok = True
        except TaskError as error:
            result.ok = False
            result.error = str(error)
            result.data = EMPTY
            rospy.logerr('server %d: task %d of robot %d rejected: %s',
                         self.server_id, task.task_id, task.robot_id, error)
        result.process_time = time.perf_counter() - start
        self.result_pub.publish(result)
        with self._lock:
            if result.ok:
                self.tasks_done += 1
            else:
                self.tasks_failed += 1

    def on_shutdown(self):
        rospy.loginfo('server %d: %d tasks done, %d rejected',
                      self.server_id, self.tasks_done, self.tasks_failed)


def main():
    run('server', ServerNode)
