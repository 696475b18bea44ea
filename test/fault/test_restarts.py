"""A node started again under its own name while the old copy still runs (an orphaned
node, a host that came back, a launch file started twice): the master tells the old copy
to shut down, the newer one serves the name, and the robots lose no task. A robot's old
copy reports each task it still had out failed as it stops; the new copy's task ids count
from 1 again (a new run).

With rospy's defaults on Debian's ROS 1.15 both copies may exit (ros_comm #2018: the old
node, shutting down, makes a master call that registers it again and bumps the new one;
rospy's log handler makes one at every log line while ``/rosout_disable_topics_generation``
is unset, ros_comm #2067). Every node of the package sets that parameter at start.
"""

import contextlib
import os
import signal
import time

import pytest
import rospy

from server_select.core.util.procs import alive, wait_until
from server_select.core.config import names
from server_select.core.flow.outcome import STOPPED
from server_select.msg import SortTask
from server_select.srv import LatencyProbe

from support.fleet import Fleet, counts
from test_faults import STABLE, TASK_TIMEOUT, answered, show, warm_up


@contextlib.contextmanager
def warm_fleet(ros):
    """The demo fleet, its tasks answered; yields (the recorder, cleared, and the fleet)."""
    rec = ros['rec']
    rec.clear()
    with Fleet(ros['log'], **STABLE) as fleet:
        warm_up(rec)
        yield rec, fleet


def probe_answers(probe):
    try:
        return probe(robot_id=99, seq=7).seq == 7
    except (rospy.ServiceException, rospy.ROSException):
        return False


@pytest.mark.parametrize('node', ['/server2', '/manager'])
def test_a_second_copy_of_a_node_takes_its_name(ros, node):
    with warm_fleet(ros) as (rec, fleet):
        old = fleet.pid(node)
        t_start = time.monotonic()
        if node == '/manager':
            fleet.restart_manager()
        else:
            fleet.restart_server(int(node[len('/server'):]))
        taken = wait_until(lambda: fleet.pid(node) not in (None, old), 30.0)
        t_taken = time.monotonic()
        old_gone = wait_until(lambda: not alive(old), 10.0)
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


def runs_of(rec, robot, since, gone_at=float('inf')):
    """Robot ``robot``'s task reports split into the old copy's run and the new copy's. Both
    count task ids from 1, and a task's report may come late (a failed task's at the task
    timeout), so ids cannot tell them apart; rospy numbers each publisher's messages
    (``header.seq``): until the old copy is gone (``gone_at``, from ``since`` on) a report
    that continues the old copy's numbering is its own, and every other is the new copy's."""
    reports = rec.of(rec.reports, robot)
    old = [r for r in reports if r.time < since]
    last = old[-1].msg.header.seq if old else 0
    new = []
    for r in reports[len(old):]:
        if r.time < gone_at and r.msg.header.seq > last:
            old.append(r)
            last = r.msg.header.seq
        else:
            new.append(r)
    return [r.msg for r in old], [r.msg for r in new]


def test_a_second_copy_of_a_robot_takes_its_name_and_no_task_is_lost(ros):
    with warm_fleet(ros) as (rec, fleet):
        old = fleet.pid('/robot1')
        t_start = time.monotonic()
        fleet.restart_robot(1)
        taken = wait_until(lambda: fleet.pid('/robot1') not in (None, old), 30.0)
        t_taken = time.monotonic()
        old_gone = wait_until(lambda: not alive(old), 10.0)
        t_gone = time.monotonic()
        new = fleet.pid('/robot1')
        works = wait_until(
            lambda: sum(m.ok for m in runs_of(rec, 1, t_start, t_gone)[1]) >= 10, 30.0)
        last_new = max((m.task_id for m in runs_of(rec, 1, t_start, t_gone)[1]), default=0)
        other = rec.outcomes((2,), TASK_TIMEOUT)[2]      # waits for late reports
        still = fleet.pid('/robot1')
    before, after = runs_of(rec, 1, t_start, t_gone)
    old_run, new_run = counts(before), counts([m for m in after if m.task_id <= last_new],
                                              last_new)
    show('a second copy of /robot1 started while the first ran:', [{
        'new copy serves the name after s': '%.2f' % (t_taken - t_start) if taken else 'never',
        'old copy exited': old_gone, 'old pid': old, 'new pid': new, 'serving at the end': still,
        'new copy answered 10 tasks': works}])
    show('tasks:', [dict(run='robot 1, old copy', **old_run),
                    dict(run='robot 1, new copy', **new_run), dict(run='robot 2', **other)])
    assert taken and old_gone and works and still == new
    # every task of the old copy reported once: answered, or failed because it stopped
    assert (old_run['never answered'], old_run['duplicates']) == (0, 0), old_run
    assert set(old_run['errors']) <= {STOPPED}, old_run
    for run in (new_run, other):
        assert (run['failed'], run['never answered'], run['duplicates']) == (0, 0, 0), run


def test_a_robot_stopped_with_tasks_out_reports_each_of_them_failed_once(ros):
    with warm_fleet(ros) as (rec, fleet):
        robot = fleet.pid('/robot1')
        sent = []                             # robot 1's tasks on the wire
        wire = rospy.Subscriber('/' + names.SORT_TASK_TOPIC, SortTask,
                                lambda t: t.robot_id == 1 and sent.append(t.task_id))
        heard = wait_until(lambda: sent, 10.0)     # connected before anything stops
        # nothing is answered: robot 1's tasks stay out (stop it before every server is
        # ejected for not answering, after which it sends nothing)
        stopped = [fleet.signal('/server%d' % s, signal.SIGSTOP) for s in (1, 2, 3)]
        try:
            del sent[:]
            out = wait_until(lambda: len(set(sent)) >= 2, 5.0)
            wire.unregister()
            os.kill(robot, signal.SIGINT)    # Ctrl-C
            exited = wait_until(lambda: not alive(robot), 15.0)
        finally:
            for pid in stopped:
                os.kill(pid, signal.SIGCONT)
        run = counts([r.msg for r in rec.of(rec.reports, 1)])
    show('robot 1 stopped (SIGINT) while every server was stopped (SIGSTOP):',
         [dict(exited=exited, **run)])
    assert heard and exited and out
    assert (run['never answered'], run['duplicates']) == (0, 0), run
    # the tasks still out, and those that found every server ejected meanwhile
    assert run['errors'][STOPPED] >= 1, run
    assert set(run['errors']) <= {STOPPED,
                                  'no server selected'}, run
