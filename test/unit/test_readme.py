"""The README's commands exist: make targets, launch files and their arguments, rosrun
executables, and the documents it links."""

import os
import re
import xml.etree.ElementTree as ET

TOP = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))


def read(*path):
    with open(os.path.join(TOP, *path)) as stream:
        return stream.read()


README = read('README.md')
# a command may continue on the next line after a backslash
COMMANDS = re.sub(r'\\\n\s*', ' ', README)


def make_targets():
    return set(re.findall(r'^([a-z][a-z0-9-]*):', read('Makefile'), re.M))


def test_the_readme_is_a_short_guide():
    assert len(README.splitlines()) <= 200


def test_every_make_target_it_names_exists():
    named = set(re.findall(r'(?<!\w)make ([a-z][a-z0-9_-]*)', README))
    assert {'demo', 'test', 'check'} <= named
    assert named - make_targets() == set()


def test_every_launch_file_and_argument_it_names_exists():
    launches = re.findall(r'roslaunch server_select (\S+\.launch)((?: [a-z_0-9]+:=\S*)*)',
                          COMMANDS)
    assert launches
    for name, args in launches:
        path = os.path.join(TOP, 'launch', name)
        assert os.path.exists(path), name
        declared = set(a.get('name') for a in ET.parse(path).getroot().iter('arg'))
        given = set(re.findall(r'([a-z_0-9]+):=', args))
        assert given - declared == set(), (name, given - declared)
    for name in re.findall(r'`([a-z_]+\.launch)`', README):
        assert os.path.exists(os.path.join(TOP, 'launch', name)), name


def test_every_rosrun_executable_and_linked_document_exists():
    for name in re.findall(r'rosrun server_select (\w+)', README):
        assert os.access(os.path.join(TOP, 'scripts', name), os.X_OK), name
    links = re.findall(r'\]\(([^)#]+)\)', README)
    assert 'docs/parameters.md' in links
    for link in links:
        assert os.path.exists(os.path.join(TOP, link)), link


def test_the_example_it_points_at_is_there_with_what_it_says():
    assert 'examples/wordcount_task' in README
    launch = re.search(r'roslaunch wordcount_task (\S+\.launch)', README).group(1)
    example = os.path.join(TOP, 'examples', 'wordcount_task')
    for part in (os.path.join('launch', launch), 'package.xml', 'msg', 'config',
                 os.path.join('test', 'wordcount.test')):
        assert os.path.exists(os.path.join(example, part)), part
