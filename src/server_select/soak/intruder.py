"""The soak's keyless node: for SECONDS, sort tasks to every server under made-up and real
robot ids, and forged flags sending every robot to the slowest server, all unsigned.

    python -m server_select.soak.intruder SECONDS

A keyed fleet must refuse all of it (and name this node, throttled) while its robots'
tasks go on as before. Prints what it sent as one line of JSON.
"""

import json
import sys
import time

import numpy as np
import rospy
from rospy.numpy_msg import numpy_msg

from server_select.core.config import names
from server_select.msg import SelectionFlag, SortTask
from server_select.soak import plan

RATE = 20.0      # messages/s on each topic


def main(argv=None):
    seconds = float((argv or sys.argv[1:])[0])
    rospy.init_node('intruder', anonymous=True)
    task_pubs = [rospy.Publisher(names.server_topic(s, names.SORT_TASK_TOPIC),
                                 numpy_msg(SortTask), queue_size=100) for s in plan.SERVERS]
    flag_pubs = [(r, rospy.Publisher(names.robot_topic(r, names.SELECTION_TOPIC),
                                     SelectionFlag, queue_size=100)) for r in plan.ROBOTS]
    time.sleep(1.0)       # connections up
    slowest = plan.SERVERS[-1]
    sent, task_id, end = {'tasks': 0, 'flags': 0}, 0, time.monotonic() + seconds
    data = np.arange(1000, 0, -1, dtype=np.int32)
    while time.monotonic() < end and not rospy.is_shutdown():
        task_id += 1
        robot = plan.ROBOTS[task_id % len(plan.ROBOTS)] if task_id % 2 else 900 + task_id % 50
        for server, pub in zip(plan.SERVERS, task_pubs):
            pub.publish(numpy_msg(SortTask)(robot_id=robot, task_id=task_id, server_id=server,
                                            data=data))
            sent['tasks'] += 1
        for robot, pub in flag_pubs:
            flag = SelectionFlag(robot_id=robot, server_id=slowest, ranking=[slowest],
                                 reason='forged')
            flag.header.stamp = rospy.Time.now()
            pub.publish(flag)
            sent['flags'] += 1
        time.sleep(1.0 / RATE)
    print(json.dumps(sent), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
