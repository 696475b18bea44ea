"""docs/parameters.md is made from the parameter table and the launch files, which agree."""

import os
import shutil

from server_select import paramdoc


def test_the_table_and_the_launch_files_agree():
    assert paramdoc.problems() == []


def test_the_parameters_document_is_current():
    with open(os.path.join(paramdoc.TOP, paramdoc.DOC)) as stream:
        assert stream.read() == paramdoc.render(), \
            'run: python3 -m server_select.paramdoc --write'


def test_every_parameter_of_the_table_is_documented():
    text = paramdoc.render()
    missing = [p for p in paramdoc.PARAMS if '`~%s`' % p not in text]
    assert missing == []


def test_a_launch_file_that_disagrees_is_named(tmp_path):
    shutil.copytree(os.path.join(paramdoc.TOP, 'launch'), str(tmp_path / 'launch'))
    path = tmp_path / 'launch' / 'server.launch'
    text = path.read_text().replace(
        'name="server_id" value="$(arg server_id)"/>',
        'name="server_id" value="$(arg server_id)"/>\n'
        '    <param name="bogus" value="$(arg bogus)"/>')
    text = text.replace('<arg name="detector" default="-" doc="haar or hog"/>',
                        '<arg name="detector" default="-" doc="haar or hog"/>\n'
                        '  <arg name="unused" default=""/>')
    path.write_text(text)
    found = paramdoc.problems(str(tmp_path))
    assert "server.launch: parameter 'bogus' is not in the table (core/settings.py)" in found
    assert "server.launch: parameter 'bogus' takes argument 'bogus', which is not " \
        'declared' in found
    assert "server.launch: argument 'unused' reaches no parameter of the node" in found
    # roslaunch --ros-args would list it as required, undocumented
    assert "server.launch: argument 'unused' has no doc" in found
    assert "server.launch: argument 'unused' defaults to \"\" (roslaunch --ros-args lists " \
        "it as required): \"-\" leaves the node's default" in found
    assert len(found) == 5, found


def test_a_launch_default_other_than_the_nodes_and_a_stale_policy_list_are_named(tmp_path):
    """robot.launch once defaulted robot_id to 1 and servers to 1,2,3 (the table: required;
    the fleet's []), and offered policies that no longer exist."""
    shutil.copytree(os.path.join(paramdoc.TOP, 'launch'), str(tmp_path / 'launch'))
    path = tmp_path / 'launch' / 'robot.launch'
    text = path.read_text().replace('<arg name="robot_id" default="-"', '<arg name="robot_id" '
                                    'default="1"')
    text = text.replace('<arg name="servers" default="-"', '<arg name="servers" '
                        'default="1,2,3"')
    text = text.replace('least_latency (the fleet)', 'bound')
    path.write_text(text)
    found = paramdoc.problems(str(tmp_path))
    assert "robot.launch: argument 'robot_id' defaults to '1', the node to required" in found
    assert "robot.launch: argument 'servers' defaults to '1,2,3', the node to required" in found
    assert any(f.startswith("robot.launch: argument 'policy' names ['bound', 'hysteresis'")
               and "'least_latency'" in f for f in found), found
    assert len(found) == 3, found
