"""A node started again under its own name while the old copy still runs (an orphaned
node, a host that came back, a launch file started twice): the master tells the old copy
to shut down, the newer one serves the name, and the robots lose no task.

With rospy's defaults on Debian's ROS 1.15 both copies may exit (ros_comm #2018: the old
node, shutting down, makes a master call that registers it again and bumps the new one;
rospy's log handler makes one at every log line while ``/rosout_disable_topics_generation``
is unset, ros_comm #2067). Every node of the package sets that parameter at start.
"""

import time

import pytest
import rospy

from server_select.core.procs import wait_until
from server_select.srv import LatencyProbe

from fleet import Fleet
from test_faults import STABLE, TASK_TIMEOUT, answered, show, warm_up


def gone(pid):
    """Whether process ``pid`` has exited (a zombie not yet reaped counts as gone)."""
    try:
        with open('/proc/%d/stat' % pid) as stream:
            return stream.read().split(')')[-1].split()[0] == 'Z'
    except OSError:
        return True


def probe_answers(probe):
    try:
        return probe(robot_id=99, seq=7).seq == 7
    except (rospy.ServiceException, rospy.ROSException):
        return False


@pytest.mark.parametrize('node', ['/server2', '/manager'])
def test_a_second_copy_of_a_node_takes_its_name(ros, node):
    rec = ros['rec']
    rec.clear()
    with Fleet(ros['log'], **STABLE) as fleet:
        warm_up(rec)
        old = fleet.pid(node)
        t_start = time.monotonic()
        if node == '/manager':
            fleet.restart_manager()
        else:
            fleet.restart_server(int(node[len('/server'):]))
        taken = wait_until(lambda: fleet.pid(node) not in (None, old), 30.0)
        t_taken = time.monotonic()
        old_gone = wait_until(lambda: gone(old), 10.0)
        new = fleet.pid(node)
        # the name stays served: still the new copy a while later, and it works
        if node == '/manager':
            works = wait_until(
                lambda: any(r.sender == node for r in rec.of(rec.flags, 1, t_taken)), 15.0)
        else:       # the robots keep their server (hysteresis): ask the new copy itself
            probe = rospy.ServiceProxy('/latency_S%s' % node[len('/server'):], LatencyProbe)
            works = wait_until(lambda: probe_answers(probe), 15.0, period=0.5)
        still = fleet.pid(node)
        assert wait_until(lambda: all(answered(rec, robot, t_taken, 10) for robot in (1, 2)),
                          20.0), 'the robots stopped being answered'
        outcomes = rec.outcomes((1, 2), TASK_TIMEOUT)
    show('a second copy of %s started while the first ran:' % node, [{
        'new copy serves the name after s': '%.2f' % (t_taken - t_start) if taken else 'never',
        'old copy exited': old_gone, 'old pid': old, 'new pid': new,
        'serving after %s' % ('a flag' if node == '/manager' else 'a probe'): still,
        'new copy works': works}])
    show('tasks:', [dict(robot=r, **o) for r, o in outcomes.items()])
    assert taken and old_gone and works and still == new
    for outcome in outcomes.values():
        assert (outcome['failed'], outcome['never answered']) == (0, 0), outcome
