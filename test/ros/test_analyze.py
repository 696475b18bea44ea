"""analyze on bags written here with the rosbag API: any bag with the topics, none without."""

import math

import pytest
import rosbag
import rospy
from std_msgs.msg import String

from server_select.core.flow.outcome import STOPPED
from server_select.msg import SelectionFlag, TaskReport
from server_select.testbed import bag_analysis
from server_select.testbed.analyze import main
from server_select.testbed.plots import plot_latency, plot_task_rtt


def write_bag(path, tasks=10, prefix=''):
    t0 = 1000.0
    with rosbag.Bag(str(path), 'w') as bag:
        for i in range(tasks):
            t = rospy.Time.from_sec(t0 + 0.5 * i)
            flag = SelectionFlag(robot_id=1, server_id=2, ranking=[2, 1],
                                 mean_latency=[0.001, 0.002]) if i < 6 else \
                SelectionFlag(robot_id=1, server_id=1, ranking=[1, 2],
                              mean_latency=[0.001, 0.003])
            bag.write(prefix + '/server_select_flag', flag, t)
            ok = i != 3
            bag.write(prefix + '/task_report', TaskReport(
                robot_id=1, task_id=i + 1, kind='sort', server_id=2, answered_by=2 if ok else -1,
                ok=ok, rtt=0.001 * (i + 1) if ok else math.nan, attempts=1), t)


def test_any_bag_with_the_topics_gives_the_table(tmp_path, capsys):
    write_bag(tmp_path / 'plain.bag')
    write_bag(tmp_path / 'fleet.bag', tasks=4, prefix='/robots_ns')  # namespaced recording
    assert main([str(tmp_path / 'plain.bag'), str(tmp_path / 'fleet.bag'),
                 '--out', str(tmp_path / 'report')]) == 0
    out = capsys.readouterr().out
    rows = [line for line in out.splitlines() if line.startswith('| plain') or
            line.startswith('| fleet')]
    assert rows[0].startswith('| plain | 10 | 1 |') and rows[1].startswith('| fleet | 4 | 1 |')
    assert (tmp_path / 'report' / 'report.md').exists()
    assert (tmp_path / 'report' / 'task_rtt.png').stat().st_size > 1000


def test_a_bag_without_the_topics_is_refused_with_one_line(tmp_path, capsys):
    path = tmp_path / 'other.bag'
    with rosbag.Bag(str(path), 'w') as bag:
        bag.write('/chatter', String(data='hello'), rospy.Time.from_sec(1.0))
    assert main([str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'has none of the topics task_report' in err[0]


@pytest.mark.parametrize('bad', ['missing.bag', 'not_a_bag.bag'])
def test_unreadable_bags_are_refused_with_one_line(tmp_path, capsys, bad):
    (tmp_path / 'not_a_bag.bag').write_text('hello')
    assert main([str(tmp_path / bad)]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_the_plots_say_what_they_show(tmp_path):
    write_bag(tmp_path / 'plain.bag')
    run = bag_analysis.load(str(tmp_path / 'plain.bag'))
    (panel,) = plot_task_rtt({'plain': run}, str(tmp_path / 'task_rtt.png'))
    assert panel['xlabel'] == 'time since the bag started (s)'
    assert panel['ylabel'] == 'task round trip (ms, log)'
    assert panel['legend'] == ['answered task', 'failed task', 'flag selects another server']
    (panel,) = plot_latency(run, str(tmp_path / 'latency.png'), 'plain')
    assert panel['xlabel'] == 'time since the bag started (s)'
    assert panel['legend'] == ['ranked by (flags) S1', 'ranked by (flags) S2',
                               'selection changed',
                               'shaded: the server the flag selects (its colour)']


def test_tasks_a_robot_still_had_out_when_it_stopped_are_left_out(tmp_path):
    write_bag(tmp_path / 'plain.bag')
    with rosbag.Bag(str(tmp_path / 'plain.bag'), 'a') as bag:
        bag.write('/task_report', TaskReport(
            robot_id=1, task_id=11, kind='sort', server_id=2, answered_by=-1, ok=False,
            rtt=math.nan, attempts=1, error=STOPPED + ' (1 attempts: servers 2)'),
            rospy.Time.from_sec(1006.0))
    reports = bag_analysis.load(str(tmp_path / 'plain.bag')).reports
    assert len(reports) == 10 and 11 not in [r.task for r in reports]
