"""What a fleet did, as seen from the manager host: run there (its ROS_MASTER_URI) by
test_multihost.py. Waits until every robot given has been flagged and has ``--tasks``
answered tasks, or ``--timeout`` s; prints one JSON line per robot (first flag and last
counted report as wall-clock times, tasks, ok, failed, answers per server, errors) and
exits 0 when every robot got there, 1 otherwise."""

import argparse
import collections
import json
import sys
import threading
import time

import rospy

from server_select.core.config import names
from server_select.msg import SelectionFlag, TaskReport


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('--robots', required=True, help='comma-separated robot ids')
    parser.add_argument('--tasks', type=int, default=10)
    parser.add_argument('--timeout', type=float, default=60.0)
    args = parser.parse_args()
    robots = [int(r) for r in args.robots.split(',')]
    lock = threading.Lock()
    seen = dict((r, {'flagged': None, 'tasks': 0, 'ok': 0, 'failed': 0, 'last': None,
                     'answered_by': collections.Counter(), 'errors': collections.Counter()})
                for r in robots)

    def on_flag(flag):
        with lock:
            if flag.robot_id in seen and seen[flag.robot_id]['flagged'] is None:
                seen[flag.robot_id]['flagged'] = time.time()

    def on_report(report):
        with lock:
            robot = seen.get(report.robot_id)
            if robot is None:
                return
            robot['tasks'] += 1
            robot['last'] = time.time()
            if report.ok:
                robot['ok'] += 1
                robot['answered_by'][str(report.answered_by)] += 1
            else:
                robot['failed'] += 1
                robot['errors'][report.error.split(' (')[0]] += 1

    def done():
        with lock:
            return all(r['flagged'] is not None and r['ok'] >= args.tasks
                       for r in seen.values())

    rospy.init_node('multihost_watch', anonymous=True, disable_signals=True)
    rospy.Subscriber(names.SELECTION_TOPIC, SelectionFlag, on_flag, queue_size=100)
    rospy.Subscriber(names.TASK_REPORT_TOPIC, TaskReport, on_report, queue_size=1000)
    end = time.monotonic() + args.timeout
    while not done() and time.monotonic() < end:
        time.sleep(0.1)
    ok = done()
    with lock:
        for robot_id, robot in sorted(seen.items()):
            print(json.dumps(dict(robot=robot_id, **robot)))
    rospy.signal_shutdown('done')
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main())
