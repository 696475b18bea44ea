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
        '<param name="server_id" value="$(arg server_id)"/>',
        '<param name="server_id" value="$(arg server_id)"/>\n'
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
