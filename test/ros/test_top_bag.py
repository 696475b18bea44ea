"""``top --bag run.bag --once``: the last view of a recorded run, its alerts stamped when
they happened in the run (they were all stamped with the bag's end)."""

import argparse

import rosbag
import rospy

from server_select.msg import LatencySample, SelectionFlag, TaskReport
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


def test_servers_the_robots_probes_reach_are_up_in_a_bag_without_announcements(tmp_path):
    """A testbed bag records samples, flags and reports but no announcements: a server
    that only answers probes is up, with the robot's round trip and ranking."""
    path = str(tmp_path / 'run.bag')
    with rosbag.Bag(path, 'w') as bag:
        for n in range(40):                 # paper probes of both servers, tasks to 1
            t = rospy.Time.from_sec(1000.0 + 0.5 * n)
            for server in (1, 2):
                bag.write('/latency_R1S%d' % server, LatencySample(
                    robot_id=1, server_id=server, seq=n, ok=True, rtt=0.001 * server), t)
            bag.write('/server_select_flag', SelectionFlag(robot_id=1, server_id=1,
                                                           ranking=[1, 2]), t)
            bag.write('/task_report', TaskReport(robot_id=1, task_id=n + 1, kind='sort',
                                                 server_id=1, answered_by=1, ok=True,
                                                 rtt=0.002, attempts=1), t)
    frame = list(bag_frames(argparse.Namespace(bag=path, once=True, speed=1e9)))[0]
    print('\n'.join(frame))
    assert '3 servers' not in frame[0] and '(2 up)' in frame[0], frame[0]
    robot = next(line.split() for line in frame if line.startswith('1 '))
    assert robot[1:4] == ['1', '1', '2'] and robot[4] == '1.0', robot   # server, ranking, ms
    assert 'GONE' not in '\n'.join(frame)
