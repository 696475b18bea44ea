"""A testbed host's CPU share is real: a busy process in a host with ``cpu: 0.2`` gets a
fifth of a core, side by side with one in a host without a limit, and the groups are gone
after the run. Needs root and the cgroup cpu controller (skipped elsewhere, with why)."""

import os
import subprocess
import sys

import pytest

from server_select.core.util.procs import measure, wait_until
from server_select.testbed.cpu import CpuLimit, controller
from server_select.testbed.linkemu import EmulatorError
from server_select.testbed import netns
from server_select.testbed.scenario import Scenario

ok, why = netns.available()
if ok:
    try:
        controller()
    except EmulatorError as error:
        ok, why = False, str(error)
pytestmark = pytest.mark.skipif(not ok, reason=why)

SPIN = [sys.executable, '-c', 'import time\nend = time.time() + 30\nwhile time.time() < end: pass']


def test_a_host_with_a_cpu_share_gets_that_share_of_a_core(tmp_path):
    data = {'name': 'cpu', 'duration': 10, 'hosts': {
        'manager': {'role': 'manager'}, 'slow': {'role': 'server', 'id': 1, 'cpu': 0.2},
        'free': {'role': 'server', 'id': 2}}}
    path = str(tmp_path / 'cpu.yaml')
    with open(path, 'w') as stream:
        stream.write(repr(data).replace("'", '"'))        # JSON is YAML
    with netns.Testbed(Scenario(data), path, str(tmp_path / 'run'), prefix='sscpu') as tb:
        slow, free = tb.popen('slow', SPIN), tb.popen('free', SPIN)
        limit = tb.limits['slow']
        assert wait_until(lambda: slow.pid in limit.pids(), 5.0), limit.pids()
        usage = measure([slow.pid, free.pid], 3.0)
        stats = limit.stats()
    shares = dict((name, usage[p.pid]['cpu_percent'] / 100.0)
                  for name, p in (('slow', slow), ('free', free)))
    print('\nCPU share of one core: limited to 0.2 -> %.3f, unlimited -> %.3f; throttled in '
          '%d of %d periods' % (shares['slow'], shares['free'], stats.get('nr_throttled', -1),
                                stats.get('nr_periods', -1)))
    assert shares['slow'] == pytest.approx(0.2, abs=0.04)
    # the other host is not limited: no group of its own, and it gets clearly more (most of
    # a core at rest; less while make test's background stream builds the catkin workspace)
    assert 'free' not in tb.limits and shares['free'] > 1.5 * shares['slow']
    assert stats.get('nr_throttled', 0) > 0
    assert netns.leftovers("sscpu") == [] and not os.path.exists(limit.path)


def test_a_cpu_share_is_checked_where_the_scenario_is_read():
    from server_select.testbed.scenario import ScenarioError
    for bad in (0.0, -1, 'fast', 100):
        with pytest.raises(ScenarioError, match='cpu'):
            Scenario({'hosts': {'manager': {'role': 'manager'},
                                's': {'role': 'server', 'id': 1, 'cpu': bad}}})
    with pytest.raises(ScenarioError, match='manager host has no CPU limit'):
        Scenario({'hosts': {'manager': {'role': 'manager', 'cpu': 0.5}}})


def test_a_process_in_a_cpu_limited_group_sees_the_cores_it_may_use():
    """What a server's ``~workers`` defaults to: its cgroup's quota rounded up. (In a
    testbed host the quota holds but cannot be read: ``ip netns exec`` mounts a /sys of
    its own, without the cgroup files; the testbed tells its servers ``workers``.)"""
    cores = len(os.sched_getaffinity(0))
    code = 'from server_select.core.util.procs import usable_cpus; print(usable_cpus())'
    seen = {}
    for share in (0.25, max(0.5, cores - 0.5)):
        limit = CpuLimit('sscpus-%g' % share, share).create()
        try:
            seen[share] = subprocess.run([sys.executable, '-c', code], preexec_fn=limit.join,
                                         stdout=subprocess.PIPE, universal_newlines=True,
                                         check=True).stdout.strip()
        finally:
            limit.remove()
    seen[None] = subprocess.run([sys.executable, '-c', code], stdout=subprocess.PIPE,
                                universal_newlines=True, check=True).stdout.strip()
    assert seen == {0.25: '1', max(0.5, cores - 0.5): str(cores), None: str(cores)}, seen
