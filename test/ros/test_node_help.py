"""``rosrun server_select <node> --help`` prints the node's parameters and exits at once,
without a master (nothing starts, nothing listens)."""

import os
import subprocess
import sys

import pytest

from server_select.core.settings import PARAMS
from server_select.paramdoc import OTHER_NODES, ROLE_FILES

SCRIPTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'scripts')
NODES = [os.path.splitext(f)[0] for f in ROLE_FILES] + sorted(OTHER_NODES)


@pytest.mark.parametrize('node', NODES)
def test_help_prints_the_parameters_and_exits(node):
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:9')     # no master there
    done = subprocess.run([sys.executable, os.path.join(SCRIPTS, node), '--help'], env=env,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=20)
    assert done.returncode == 0, done.stdout
    assert done.stdout.startswith('usage: rosrun server_select %s' % node), done.stdout
    listed = [line.split()[0] for line in done.stdout.splitlines() if line.startswith('  ~')]
    assert listed and all(p in PARAMS for p in (name[1:] for name in listed)), done.stdout
