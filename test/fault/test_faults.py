"""Fault tests: a real roscore and the demo fleet (manager, 3 servers, 2 robots, sort tasks
at 5 Hz), faults injected with real signals. Each test prints its counts.

The kill / stop / spoof tests run with ``hysteresis:=0.01``: on loopback every server is
equally near, and without it the selection flaps between them by itself, which would hide
whether the robot moved because of the fault.
"""

import collections
import json
import os
import signal
import subprocess
import sys
import time
import xmlrpc.client

import pytest
import rosgraph

from server_select.bench.harness import master_up
from server_select.core.ranking.rank import NO_SERVER
from server_select.core.util.procs import stop_group, wait_until

from support.fleet import NODES, Fleet, kill

HERE = os.path.dirname(os.path.abspath(__file__))
TASK_TIMEOUT = 2.0   # the robots' default
STABLE = {'task_rate': 5, 'hysteresis': 0.01}


def current_server(rec, robot):
    answered = [r.msg.answered_by for r in rec.of(rec.reports, robot) if r.msg.ok]
    return answered[-1] if answered else None


def first_elsewhere(rec, robot, victim, since, timeout=10.0):
    """Seconds from ``since`` to the first answer of ``robot``'s tasks by another server."""
    def found():
        return next((r for r in rec.of(rec.reports, robot, since)
                     if r.msg.ok and r.msg.answered_by != victim), None)
    wait_until(lambda: found() is not None, timeout)
    hit = found()
    return hit.time - since if hit else None


def ranked(rec, robot, server, since):
    """Whether the manager's newest flag for ``robot`` since ``since`` ranks ``server``
    (None: no flag yet)."""
    flags = [r for r in rec.of(rec.flags, robot, since) if r.sender == '/manager']
    return server in flags[-1].msg.ranking if flags else None


def answered(rec, robot, since, tasks, by=None):
    """Whether ``tasks`` of ``robot``'s tasks were answered since ``since``: by any server
    (``by`` None), or by the servers ``by(server)`` accepts."""
    return sum(1 for r in rec.of(rec.reports, robot, since)
               if r.msg.ok and (by is None or by(r.msg.answered_by))) >= tasks


def warm_up(rec, robots=(1, 2), tasks=10):
    def ok():
        return dict((robot, sum(1 for r in rec.of(rec.reports, robot) if r.msg.ok))
                    for robot in robots)
    assert wait_until(lambda: min(ok().values()) >= tasks, 40.0), \
        'tasks answered in 40 s, by robot: %s; %s' % (
            ok(), dict((robot, rec.failures(robot)) for robot in robots))


def show(title, rows):
    print('\n%s' % title)
    for row in rows:
        print('  ' + ', '.join('%s %s' % kv for kv in row.items()))


@pytest.mark.parametrize('how', ['SIGKILL', 'SIGSTOP'])
def test_selected_server_fails_three_times(ros, how):
    rec = ros['rec']
    rec.clear()
    cycles = []
    with Fleet(ros['log'], **STABLE) as fleet:
        warm_up(rec)
        for cycle in range(3):
            victim = current_server(rec, 1)
            node = '/server%d' % victim
            pid = fleet.pid(node)
            t_fault = time.monotonic()
            os.kill(pid, signal.SIGKILL if how == 'SIGKILL' else signal.SIGSTOP)
            moved = first_elsewhere(rec, 1, victim, t_fault)
            # down until the manager has dropped it from robot 1's ranking (its window
            # holds no answer of it any more), then back
            dropped = wait_until(lambda: ranked(rec, 1, victim, t_fault) is False, 20.0)
            t_dropped = time.monotonic()
            if how == 'SIGKILL':
                fleet.restart_server(victim)
            else:
                os.kill(pid, signal.SIGCONT)
            assert wait_until(lambda: fleet.pid(node) not in (None, pid if how == 'SIGKILL'
                                                              else None), 20.0)
            back = wait_until(lambda: ranked(rec, 1, victim, t_dropped), 20.0)
            assert dropped and back, (cycle, victim, dropped, back)
            cycles.append({'cycle': cycle + 1, 'server': victim, 'at': round(t_fault, 2),
                           'first answer elsewhere after s': '%.3f' % moved
                           if moved is not None else 'never'})
        outcomes = rec.outcomes((1, 2), TASK_TIMEOUT)
    show('%s of robot 1\'s server, 3 cycles:' % how, cycles)
    show('tasks:', [dict(robot=r, **o) for r, o in outcomes.items()])
    for robot, outcome in outcomes.items():
        assert (outcome['never answered'], outcome['duplicates']) == (0, 0), \
            'robot %d: %s' % (robot, outcome)
        assert outcome['failed'] == 0, 'robot %d: %s; %s; cycles %s' % (
            robot, outcome, rec.failures(robot), cycles)
    assert all(c['first answer elsewhere after s'] != 'never' for c in cycles), cycles
    assert max(float(c['first answer elsewhere after s']) for c in cycles) <= 1.0, cycles


def test_a_robot_stalled_longer_than_the_window_goes_on_with_its_server(ros):
    # robot 1 stopped (SIGSTOP) until the manager, with no sample of it in its 5 s window,
    # flags it no server: when it runs again its own window is empty as well, and its
    # next tasks go out before its next probe is answered. Its server did nothing wrong:
    # they go to it (before: each failed, "no server selected").
    rec = ros['rec']
    rec.clear()
    with Fleet(ros['log'], **STABLE) as fleet:
        warm_up(rec)
        before = current_server(rec, 1)
        pid, t_stop = fleet.pid('/robot1'), time.monotonic()
        os.kill(pid, signal.SIGSTOP)
        try:
            emptied = wait_until(lambda: any(r.msg.server_id == NO_SERVER for r in rec.of(
                rec.flags, 1, t_stop) if r.sender == '/manager'), 20.0)
        finally:
            os.kill(pid, signal.SIGCONT)
        t_cont = time.monotonic()
        resumed = wait_until(lambda: answered(rec, 1, t_cont, 10), 20.0)
        after = [r.msg for r in rec.of(rec.reports, 1, t_cont)]
        outcomes = rec.outcomes((1, 2), TASK_TIMEOUT)
    woke = {'robot 1 after it resumed: reports': len(after),
            'answered': sum(1 for m in after if m.ok), 'by server': sorted(set(
                m.answered_by for m in after if m.ok)), 'server before': before,
            'errors': collections.Counter(m.error.split(' (')[0] for m in after if not m.ok)}
    show('robot 1 stopped until the manager flagged it no server (%.1f s), then resumed:'
         % (t_cont - t_stop), [dict(robot=r, **o) for r, o in outcomes.items()] + [woke])
    assert emptied and resumed, (emptied, resumed)
    assert woke['errors']['no server selected'] == 0, woke
    # (tasks out when it stopped may have timed out by the time it runs again)
    for robot, outcome in outcomes.items():
        assert (outcome['never answered'], outcome['duplicates']) == (0, 0), outcome
    assert outcomes[2]['failed'] == 0, outcomes[2]


def test_manager_gone_then_the_selected_server_dies(ros):
    rec = ros['rec']
    rec.clear()
    with Fleet(ros['log'], **STABLE) as fleet:
        warm_up(rec)
        kill(fleet, '/manager')
        t_gone = time.monotonic()
        assert wait_until(lambda: all(rec.log_lines('/robot%d' % robot, 'ranking servers from '
                                                    'its own probes') for robot in (1, 2)),
                          10.0), 'the robots did not notice that the manager is gone'
        alone = time.monotonic() - t_gone
        victim = current_server(rec, 1)
        t_kill = time.monotonic()
        kill(fleet, '/server%d' % victim)
        moved = first_elsewhere(rec, 1, victim, t_kill)
        # the robots go on alone: 10 more tasks of robot 1 answered elsewhere
        assert wait_until(lambda: answered(rec, 1, t_kill, 10, lambda s: s != victim), 10.0)
        fleet.restart_manager()
        t_restart = time.monotonic()
        # from when the new manager answers its master, not from its process's start (a
        # python node's imports took seconds of it on a host running three test streams)
        assert wait_until(lambda: fleet.pid('/manager') is not None, 20.0), \
            'the new manager did not come up'
        t_back = time.monotonic()

        def flagged(robot):
            return any(r.sender == '/manager' for r in rec.of(rec.flags, robot, t_back))
        assert wait_until(lambda: flagged(1) and flagged(2), 10.0), 'no flag from the new manager'
        back = max(min(r.time for r in rec.of(rec.flags, robot, t_back)) for robot in (1, 2))
        assert wait_until(lambda: all(answered(rec, robot, back, 10) for robot in (1, 2)), 10.0)
        outcomes = rec.outcomes((1, 2), TASK_TIMEOUT)
    own = [rec.log_lines('/robot%d' % robot, 'ranking servers from its own probes')
           for robot in (1, 2)]
    show('manager killed, then server %d (robot 1\'s):' % victim, [{
        'robots deciding alone after s': '%.2f' % alone,
        'first answer elsewhere after s': '%.3f' % moved if moved is not None else 'never',
        'new manager up after s': '%.2f' % (t_back - t_restart),
        'every robot flagged by the new manager after s': '%.2f' % (back - t_back),
        'robots that said they decide alone': sum(1 for lines in own if lines)}])
    show('tasks:', [dict(robot=r, **o) for r, o in outcomes.items()])
    for outcome in outcomes.values():
        assert (outcome['never answered'], outcome['duplicates'], outcome['failed']) == \
            (0, 0, 0), outcome
        assert 'no server selected' not in outcome['errors']
    assert all(own), 'each robot logs once that it decides locally'
    assert back - t_back <= 5.0          # within one window


def test_forged_samples_flags_and_results_change_nothing(ros):
    rec = ros['rec']
    rec.clear()
    with Fleet(ros['log'], **STABLE):
        warm_up(rec)
        ours = current_server(rec, 1)
        forged = [s for s in (1, 2, 3) if s != ours][0]
        t_spoof = time.monotonic()
        out = subprocess.run([sys.executable, os.path.join(HERE, 'spoofer.py'), str(forged),
                              '8'], stdout=subprocess.PIPE, universal_newlines=True,
                             timeout=60, check=True)
        sent = json.loads(out.stdout.strip().splitlines()[-1])
        t_end = time.monotonic()
        during = [r.msg for r in rec.of(rec.reports, 1, t_spoof) if r.time <= t_end]
        means = [m for r in rec.of(rec.flags, 1, t_spoof) if r.sender == '/manager'
                 for s, m in zip(r.msg.ranking, r.msg.mean_latency) if s == forged]
        outcome = rec.outcomes((1,), TASK_TIMEOUT)[1]
    warnings = {'manager': rec.log_lines('/manager', '/spoofer'),
                'robot 1': rec.log_lines('/robot1', '/spoofer')}
    show('spoofer (as server %d; robot 1 uses server %d):' % (forged, ours), [
        dict(('forged ' + k, v) for k, v in sent.items()),
        {'robot 1 tasks meanwhile': len(during),
         'sent to the forged server': sum(1 for m in during if m.server_id == forged),
         'failed': sum(1 for m in during if not m.ok),
         'lowest mean the manager published for it, ms': '%.3f' % (min(means) * 1e3)
         if means else '-',
         'warnings naming /spoofer (manager, robot 1)': '%d, %d' % (
             len(warnings['manager']), len(warnings['robot 1']))}])
    assert min(sent['samples'], sent['flags']) > 100 and sent['results'] > 20
    assert len(during) >= 30
    assert [m.server_id for m in during if m.server_id == forged] == []
    assert [m for m in during if not m.ok] == [] and outcome['failed'] == 0
    assert all(m > 1e-5 for m in means), means   # the 0.1 us samples never entered a mean
    assert warnings['manager'] and warnings['robot 1'], warnings


def system_state():
    return rosgraph.Master('/fault_tests').getSystemState()


def fleet_whole():
    """Every fleet registration is back at the master, and server 3 (restarted after the
    master) has its /data connections from both robots."""
    try:
        return _fleet_whole()
    except (OSError, xmlrpc.client.Error, rosgraph.MasterError):
        return False   # e.g. the master still names the killed server 3


def _fleet_whole():
    pubs, subs, _ = system_state()
    pubs, subs = dict(pubs), dict(subs)
    if not {'/robot1', '/robot2'} <= set(pubs.get('/data', ())) or \
            set(pubs.get('/server_select_flag', ())) != {'/manager'} or \
            not {'/server1', '/server2', '/server3'} <= set(subs.get('/data', ())):
        return False
    uri = rosgraph.Master('/fault_tests').lookupNode('/server3')
    _, _, bus = xmlrpc.client.ServerProxy(uri).getBusInfo('/fault_tests')
    master = rosgraph.Master('/fault_tests')
    robots = set(master.lookupNode(r) for r in ('/robot1', '/robot2'))
    inbound = set(b[1] for b in bus if b[4] == '/data' and b[2] == 'i' and b[5])
    return robots <= inbound


def test_roscore_restart(ros):
    rec = ros['rec']
    rec.clear()
    core = ros['core']
    with Fleet(ros['log'], task_rate=5) as fleet:
        warm_up(rec)
        # roscore's every process: roslaunch, rosmaster and rosout (each in a process
        # group of its own: a rosout left running would outlive the tests)
        master_pid, rosout_pid = rosgraph.Master('/fault_tests').getPid(), fleet.pid('/rosout')
        stop_group(core.proc, signal.SIGKILL)
        for pid in (master_pid, rosout_pid):
            if pid is not None:
                os.kill(pid, signal.SIGKILL)
        t_down = time.monotonic()
        # the master is down until 40 tasks were answered without it (at 5 Hz, 4 s)
        wait_until(lambda: answered(rec, 1, t_down, 20) and answered(rec, 2, t_down, 20), 15.0)
        down_for = time.monotonic() - t_down
        while_down = [r.msg for r in rec.of(rec.reports, since=t_down)]
        core.proc = subprocess.Popen(['roscore', '-p', str(core.port)],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                     start_new_session=True)
        t_start = time.monotonic()
        # roscore's own start (roslaunch, rosmaster, rosout) is not the fleet's recovery:
        # the nodes' 20 s begin once the new master answers
        assert wait_until(lambda: master_up(core.uri), 60.0), \
            'the new roscore did not answer in 60 s'
        t_up = time.monotonic()
        assert wait_until(lambda: all(fleet.pid(n) for n in NODES), 20.0), system_state()
        t_registered = time.monotonic()
        kill(fleet, '/server3')                # a node that joins the new master
        fleet.restart_server(3)

        def ranked():
            return all(any(len(r.msg.ranking) == 3 for r in rec.of(rec.flags, robot, t_up))
                       for robot in (1, 2))
        whole = wait_until(lambda: ranked() and fleet_whole(), 30.0, period=0.2)
        t_whole = time.monotonic()
        outcomes = rec.outcomes((1, 2), TASK_TIMEOUT)
    show('roscore killed for %.1f s, then restarted:' % down_for, [{
        'roscore answering after s': '%.2f' % (t_up - t_start),
        'every node registered again after s': '%.2f' % (t_registered - t_up),
        'tasks answered while it was down': sum(1 for m in while_down if m.ok),
        'failed while down': sum(1 for m in while_down if not m.ok),
        'fleet whole again after s': '%.2f' % (t_whole - t_up) if whole else 'never'}])
    show('tasks:', [dict(robot=r, **o) for r, o in outcomes.items()])
    assert sum(1 for m in while_down if m.ok) >= 40 and not any(not m.ok for m in while_down)
    assert whole, system_state()
    for outcome in outcomes.values():
        assert (outcome['never answered'], outcome['duplicates']) == (0, 0), outcome
