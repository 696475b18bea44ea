"""What a testbed run waits for before a ``time_zero: ready`` scenario's time starts: the
node each of the package's launch files starts, named as roslaunch itself names it (a file
whose default name changed would leave a run waiting for a node that never registers)."""

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
