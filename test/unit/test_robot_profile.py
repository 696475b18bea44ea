"""bench-robot: each sampled stack goes to the part of the robot it is in; the launch
file it runs."""

import argparse
import xml.etree.ElementTree as ET

import pytest

from server_select.bench.robot_cost import cells, launch_args, launch_file
from server_select.bench.robot_profile import part_of, parts, table

PROBE = ('_run (server_select/ros/probe_loop.py:116)',
         '_answer (server_select/ros/probe_loop.py:140)',
         'read_answer (server_select/ros/probe_client.py:104)',
         'read_messages (rospy/impl/tcpros_service.py:361)')


def test_the_innermost_frame_of_ours_decides_and_waiting_is_left_out():
    assert part_of(list(PROBE)) == 'probes'
    assert part_of(['_act (server_select/ros/task_stream.py:87)',
                    'publish (server_select/ros/seal.py:210)',       # a wrapper: its caller
                    'publish (rospy/topics.py:882)']) == 'task path'
    assert part_of(['x (server_select/ros/seal.py:1)',
                    'sign (server_select/core/trust/seal.py:9)']) == 'seal'
    assert part_of(['run (rospy/timer.py:237)', 'sleep (rospy/timer.py:113)']) is None
    assert part_of(['run (rospy/timer.py:237)', '__init__ (genpy/rostime.py:65)']) == \
        'rospy timers'
    assert part_of(['x (server_select/ros/prober.py:1)', 'info (logging/__init__.py:1)']) == \
        'logging'
    assert part_of(['receive_once (rospy/impl/tcpros_base.py:744)',
                    'recv_buff (rospy/impl/tcpros_base.py:106)']) is None


def test_parts_add_up_the_samples_and_the_table_gives_shares():
    counted = parts([';'.join(PROBE) + ' 30\n', 'run (rospy/timer.py:237);'
                     'x (genpy/rostime.py:1) 10\n', 'garbage\n'])
    assert counted == {'probes': 30, 'rospy timers': 10}
    text = table({'fleet': counted, 'paper': {'probes': 5}})
    assert '| probes | 75.0 | 100.0 |' in text and '| samples on a CPU | 40 | 5 |' in text


def test_the_robot_bench_passes_more_robot_arguments_to_both_robots(tmp_path):
    extra = launch_args('contender_budget:=6 window:=2.0')
    assert extra == {'contender_budget': '6', 'window': '2.0'}
    for bad in ('contender_budget=6', ':=6'):
        with pytest.raises(argparse.ArgumentTypeError):
            launch_args(bad)
    for profile in ('paper', 'fleet'):
        path = tmp_path / ('%s.launch' % profile)
        launch_file(str(path), profile, cells('here:sort:4')[0], extra)
        robot = [node for node in ET.parse(str(path)).getroot().iter('include')
                 if node.get('file').endswith('/robot.launch')][0]
        args = dict((arg.get('name'), arg.get('value')) for arg in robot.iter('arg'))
        assert args['contender_budget'] == '6' and args['window'] == '2.0', args
        assert args['profile'] == profile and args['task_rate'] == '2'
