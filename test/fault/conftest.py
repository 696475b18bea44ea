"""A roscore of the fault tests' own, and this process as a ROS node recording the fleet."""

import os
import sys

import pytest

sys.path.append(os.path.join(os.path.dirname(__file__), '..', '..', 'src'))

import rospy  # noqa: E402

from server_select.bench.harness import Roscore  # noqa: E402
from server_select.core.trust.keys import make_key  # noqa: E402
from server_select.ros.master_watch import MasterWatch  # noqa: E402

from support.fleet import Recorder  # noqa: E402


@pytest.fixture(scope='session')
def ros(tmp_path_factory):
    log_dir = str(tmp_path_factory.mktemp('faults'))
    core = Roscore(log_dir)
    core.__enter__()
    rospy.init_node('fault_tests', disable_signals=True)
    watch = MasterWatch(0.5)
    watch.start()
    state = {'core': core, 'log': os.path.join(log_dir, 'fleet.log'), 'rec': Recorder()}
    yield state
    rospy.signal_shutdown('fault tests done')
    state['core'].__exit__()


@pytest.fixture
def fleet_key(tmp_path):
    """A new fleet key file (mode 0600), for a fleet whose every node gets it."""
    path = str(tmp_path / 'fleet.key')
    make_key(path)
    return path
