"""``top --bag run.bag --once``: the last view of a recorded run, its alerts stamped when
they happened in the run (they were all stamped with the bag's end)."""

import argparse

import rosbag
import rospy

from server_select.msg import TaskReport
from server_select.nodes.top import bag_frames


def test_a_server_that_went_mid_run_is_alerted_at_its_time_in_the_last_view(tmp_path):
    path = str(tmp_path / 'run.bag')
    with rosbag.Bag(path, 'w') as bag:
        for n in range(60):                 # 2 a second for 30 s; server 2 answers until 10 s
            t = 1000.0 + 0.5 * n
            server = 2 if t < 1010.0 else 1
            bag.write('/task_report', TaskReport(robot_id=1, task_id=n + 1, kind='sort',
                                                 server_id=server, answered_by=server,
                                                 ok=True, rtt=0.002, attempts=1),
                      rospy.Time.from_sec(t))
    frames = list(bag_frames(argparse.Namespace(bag=path, once=True, speed=1e9)))
    assert len(frames) == 1
    alerts = frames[0][frames[0].index('ALERTS') + 1:]
    print('\n'.join(alerts))
    gone = [line for line in alerts if 'server 2 gone' in line]
    assert gone and 1011.5 <= float(gone[0].split()[0]) <= 1013.0, alerts
