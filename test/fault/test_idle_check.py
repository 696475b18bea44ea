"""A slowed server nobody sends to says so, and says when it recovers: a real server node
(``~check_every`` 2 s, ``~test_knobs``) does this node's sort tasks, which then stop; its
``~work_delay`` is set to 0.2 s (a busy machine) and later back to 0. Its probe answers'
work for the sort kind follows both, from checks alone (a copy of its last task timed while
no robot sends there); without, they would say what its history says (1 ms) until a robot
sent it a task. Printed: the seconds until each shows, the checks the server counted.
Asserted: both show within the arrivals' horizon (10 s) + two checks, its summary comes to
count the four checks that needs (waited for), and no check's result reaches anybody
(every task answered once)."""

import subprocess
import sys
import time

import rosgraph
import rospy

from server_select.core.util.procs import stop_group, wait_until
from server_select.msg import SortResult, SortTask
from server_select.srv import LatencyProbe

from support.record import until_answered

SERVER, ROBOT = 9, 7
SLOW = 0.2                  # s a task takes more while the server is slowed
# s: its last task's arrival forgotten (10 s at most), then two checks, 2 s apart, or 4 s
# apart once a task takes 0.2 s (checks take at most a twentieth of a worker)
SHOWS_BY = 16.0


def checks_counted(tmp_path):
    """The checks the server's newest summary line counts (0: none yet)."""
    with open(str(tmp_path / 'server.log')) as log:
        lines = [line for line in log if 'checks of an idle kind' in line]
    return int(lines[-1].split(', ')[-1].split()[0]) if lines else 0


def work_reported(probe, seq):
    answer = probe(robot_id=ROBOT, seq=seq, stamp=rospy.Time.now())
    return dict(zip(answer.kinds, answer.service_time)).get('sort')


def until_reported(probe, condition, timeout):
    """Seconds until the server's probe answers report sort work meeting ``condition``
    (None: not within ``timeout``), probed every 0.25 s."""
    start, seq = time.monotonic(), [0]

    def met():
        seq[0] += 1
        work = work_reported(probe, seq[0])
        return work is not None and condition(work)
    return time.monotonic() - start if wait_until(met, timeout, period=0.25) else None


def test_a_slowed_server_nobody_uses_says_so_and_when_it_recovers(ros, tmp_path):
    results, lines = [], []
    rospy.Subscriber('/processed_data', SortResult, lambda r: results.append(r)
                     if r.robot_id == ROBOT else None, queue_size=100)
    tasks = rospy.Publisher('/data', SortTask, queue_size=100)
    with open(str(tmp_path / 'server.log'), 'w') as log:
        server = subprocess.Popen(
            ['rosrun', 'server_select', 'server', '_server_id:=%d' % SERVER,
             '_check_every:=2', '_test_knobs:=true', '_summary_period:=1',
             '__name:=server%d' % SERVER], stdout=log, stderr=subprocess.STDOUT,
            start_new_session=True)
    try:
        rospy.wait_for_service('/latency_S%d' % SERVER, 30.0)
        probe = rospy.ServiceProxy('/latency_S%d' % SERVER, LatencyProbe)
        sent = [0]

        def send():
            sent[0] += 1
            tasks.publish(SortTask(robot_id=ROBOT, task_id=sent[0], server_id=SERVER,
                                   data=list(range(2000, 0, -1))))
        assert until_answered(send, lambda: len(results) >= 1, timeout=20.0)
        wired = sent[0]          # (one sent before the server heard the topic is lost)
        for _ in range(5):
            send()
        assert wait_until(lambda: set(range(wired + 1, sent[0] + 1)) <= set(
            r.task_id for r in results), 10.0), (sent[0], [r.task_id for r in results])
        before = len(results)
        fast = work_reported(probe, 0)
        rosgraph.Master('/fault_tests').setParam('/server%d/work_delay' % SERVER, SLOW)
        slowed = until_reported(probe, lambda work: work >= SLOW, SHOWS_BY + 10.0)
        rosgraph.Master('/fault_tests').setParam('/server%d/work_delay' % SERVER, 0.0)
        recovered = until_reported(probe, lambda work: work < SLOW / 2, SHOWS_BY + 10.0)
        # its summary (every 1 s) counts the checks: two slow ones to show the slowdown,
        # two fast ones its end; by then a check's result, were there one, is in too
        counted = wait_until(lambda: checks_counted(tmp_path) >= 4, 10.0, period=0.2)
        ids = [r.task_id for r in results]
    finally:
        stop_group(server)
    with open(str(tmp_path / 'server.log')) as log:
        lines = [line for line in log if 'checks of an idle kind' in line]
    print('\nsort work reported: %.4f s; slowed by %g s: shown after %s s, recovered: after '
          '%s s; %d tasks sent, %d results (%d before the slowdown); last summary: %s'
          % (fast, SLOW, slowed and '%.1f' % slowed, recovered and '%.1f' % recovered,
             sent[0], len(ids), before, lines[-1].strip() if lines else '-'))
    sys.stdout.flush()
    assert fast < SLOW / 2
    assert slowed is not None and slowed <= SHOWS_BY, slowed
    assert recovered is not None and recovered <= SHOWS_BY, recovered
    assert len(ids) == before == len(set(ids))     # no check's result went anywhere
    assert counted, lines[-1:]
