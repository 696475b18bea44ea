#!/usr/bin/env python3
"""A careless (or hostile) node: fake samples, flags and results for robot 1.

    spoofer.py SERVER SECONDS [NAME [ROBOT_KEY]]

registers as node NAME (default spoofer; ``manager`` takes the manager's name, and the
master shuts the real one down), publishes at 20 Hz a 0.1 us round trip for robot 1 /
SERVER on latency_R1S<SERVER>, a flag sending robot 1 to SERVER (on the shared flag topic and
on robot 1's own), and, for every sort task
robot 1 sends, a "result" claiming the addressed server with wrong data (all unsigned, or,
with ROBOT_KEY, a robot's role key file as a compromised robot holds it, signed with that);
prints what it sent as one line of JSON.
"""

import json
import sys
import time

import numpy as np
import rospy
from rospy.numpy_msg import numpy_msg

from server_select.core.config import names
from server_select.core.trust.seal import Sealer, load_keys
from server_select.msg import LatencySample, SelectionFlag, SortResult, SortTask
from server_select.ros.seal import sealed


def main():
    server, seconds = int(sys.argv[1]), float(sys.argv[2])
    rospy.init_node(sys.argv[3] if len(sys.argv) > 3 else 'spoofer', disable_signals=True)
    sent = {'samples': 0, 'flags': 0, 'results': 0}
    sealer = Sealer(load_keys(sys.argv[4], 'robot'), rospy.get_name()) \
        if len(sys.argv) > 4 else None

    def send(pub, msg):
        pub.publish(sealed(msg, sealer, pub.resolved_name))
    samples = rospy.Publisher(names.sample_topic(1, server), LatencySample, queue_size=10)
    flags = [rospy.Publisher(topic, SelectionFlag, queue_size=10) for topic in
             (names.SELECTION_TOPIC, names.robot_topic(1, names.SELECTION_TOPIC))]
    results = rospy.Publisher(names.SORT_RESULT_TOPIC, numpy_msg(SortResult), queue_size=100)

    def forge(task):
        if task.robot_id == 1:
            send(results, SortResult(header=task.header, robot_id=1, task_id=task.task_id,
                                     server_id=task.server_id, ok=True,
                                     data=np.zeros(len(task.data), dtype=np.int32)))
            sent['results'] += 1
    rospy.Subscriber(names.SORT_TASK_TOPIC, numpy_msg(SortTask), forge, tcp_nodelay=True)
    time.sleep(1.0)   # let the connections come up
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        sample = LatencySample(robot_id=1, server_id=server, ok=True, rtt=1e-7)
        sample.header.stamp = rospy.Time.now()
        send(samples, sample)
        for pub in flags:
            send(pub, SelectionFlag(robot_id=1, server_id=server, ranking=[server],
                                    mean_latency=[1e-7], sample_count=[1]))
        sent['samples'] += 1
        sent['flags'] += 1
        time.sleep(0.05)
    print(json.dumps(sent), flush=True)


if __name__ == '__main__':
    main()
