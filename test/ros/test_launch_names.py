"""What a testbed run waits for before a ``time_zero: ready`` scenario's time starts: the
node each of the package's launch files starts, named as roslaunch itself names it (a file
whose default name changed would leave a run waiting for a node that never registers).
And what the demo's robots wait for before their first task."""

import os

import pytest
import roslaunch.config

from server_select.testbed.runner import node_of

LAUNCH = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'launch')


@pytest.mark.parametrize('launch, args', [
    ('server.launch', ['server_id:=3', 'profile:=fleet']),
    ('robot.launch', ['robot_id:=12', 'mode:=fixed']),
    ('robot.launch', ['robot_id:=1', 'name:=scout']),
    ('manager.launch', ['profile:=fleet']),
    ('manager.launch', ['group:=2']),
    ('manager.launch', ['name:=manager_fleet']),
    ('oracle.launch', ['t0:=1.5', 'scenario:=x.yaml', 'robots:=1'])])
def test_the_node_a_launch_starts_is_the_one_roslaunch_names(launch, args):
    config = roslaunch.config.load_config_default([(os.path.join(LAUNCH, launch), args)],
                                                  None, verbose=False)
    names = [n.namespace + n.name for n in config.nodes if n.package == 'server_select']
    assert names == [node_of(launch, args)]


def test_another_launch_file_is_not_waited_for():
    assert node_of('search_demo.launch', []) is None


@pytest.mark.parametrize('args, listeners', [
    (['duration:=90'], 'report'),
    (['duration:=90', 'report_listeners:=/recorder'], '/recorder report'),
    (['report_listeners:=/recorder'], '/recorder'),
    ([], None)])
def test_the_demos_robots_wait_for_its_report_node_to_hear_them(args, listeners):
    """With a duration the demo's report node sums up every task report: each robot waits
    for it to hear them (a subscriber left unconnected by two registrations at once made
    its summary say that a robot of 3 loopback runs sent nothing)."""
    config = roslaunch.config.load_config_default([(os.path.join(LAUNCH, 'demo.launch'), args)],
                                                  None, verbose=False)
    found = dict((k, v.value) for k, v in config.params.items() if k.endswith('/report_listeners'))
    robots = [n.namespace + n.name for n in config.nodes if n.type == 'robot']
    assert len(robots) == 2
    assert found == ({} if listeners is None else
                     dict((r + '/report_listeners', listeners) for r in robots)), found
