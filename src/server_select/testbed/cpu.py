"""Real CPU capacity for testbed hosts: a cgroup with a CPU quota (no rospy).

A scenario host with ``cpu: 0.25`` gets a cgroup ``server_select/<prefix>-<host>`` whose
quota is a quarter of one core (``cpu.cfs_quota_us`` / ``cpu.cfs_period_us`` with the
cgroup v1 ``cpu`` controller, ``cpu.max`` with cgroup v2); every process the testbed starts
in the host joins it before it runs, and whatever it starts later inherits it. Its work
is then really slower: no sleep pretends to be work. Needs root.

The quota is given per period (``cpu_period``, 100 ms by default): with a long period a
capped process runs flat out until the quota is spent and then stalls for the rest of
the period (a 0.1 share: 10 ms running, 90 ms stopped); with a period of a few ms it is
slowed more evenly, as a slower processor would be (the kernel charges the quota at its
tick, 4 ms at HZ=250: a 0.2 share per 5 ms runs about a tick and waits about four, where
a 100 ms period stops it for 80 ms). A host may also get a memory limit
(``memory``, MiB: the ``memory`` controller's ``memory.limit_in_bytes``, ``memory.max``
with cgroup v2).
"""

import errno
import os

from server_select.testbed.fields import DEFAULT_CPU_PERIOD_MS
from server_select.testbed.linkemu import EmulatorError

V1 = '/sys/fs/cgroup/cpu'
V2 = '/sys/fs/cgroup'
GROUP = 'server_select'
PERIOD_US = int(DEFAULT_CPU_PERIOD_MS * 1000)
MEMORY_V1 = '/sys/fs/cgroup/memory'


def controller():
    """``('v1' or 'v2', root folder)`` of the cgroup cpu controller; EmulatorError (one
    line saying what is missing) where there is none to use."""
    if os.path.exists(os.path.join(V1, 'cpu.cfs_quota_us')):
        return 'v1', V1
    try:
        with open(os.path.join(V2, 'cgroup.controllers')) as stream:
            if 'cpu' in stream.read().split():
                return 'v2', V2
    except OSError:
        pass
    raise EmulatorError('CPU limits (a host\'s "cpu:") need the cgroup cpu controller: '
                        'neither %s/cpu.cfs_quota_us (cgroup v1) nor "cpu" in '
                        '%s/cgroup.controllers (cgroup v2) is here' % (V1, V2))


def _write(path, text):
    with open(path, 'w') as stream:
        stream.write(text)


class CpuLimit(object):
    """One host's cgroup: ``share`` of one core (0.25: a quarter; 2: two cores), given per
    ``period_us``; with ``memory_mb``, also a memory limit."""

    def __init__(self, name, share, period_us=PERIOD_US, memory_mb=None):
        if not share >= 0.01:
            raise ValueError('a CPU share must be at least 0.01 of a core, got %r' % (share,))
        if not 1000 <= period_us <= 1000000:
            raise ValueError('a CFS period must be 1 ms to 1 s, got %r us' % (period_us,))
        # the kernel's least quota is 1 ms: a smaller share gets a longer period
        self.name, self.share = name, float(share)
        self.period_us = max(int(period_us), int(-(-1000 // self.share)))
        self.memory_mb = memory_mb
        self.version, root = controller()
        self.parent = os.path.join(root, GROUP)
        self.path = os.path.join(self.parent, name)
        self.memory_path = os.path.join(MEMORY_V1, GROUP, name) \
            if memory_mb and self.version == 'v1' else None

    def create(self):
        if self.version == 'v2':      # the controllers must be on down to our groups
            _write(os.path.join(V2, 'cgroup.subtree_control'),
                   '+cpu +memory' if self.memory_mb else '+cpu')
        os.makedirs(self.path, exist_ok=True)
        quota = int(round(self.share * self.period_us))
        if self.version == 'v1':
            # the quota may not exceed the old period's: the period first when it shrinks
            _write(os.path.join(self.path, 'cpu.cfs_quota_us'), '-1')
            _write(os.path.join(self.path, 'cpu.cfs_period_us'), str(self.period_us))
            _write(os.path.join(self.path, 'cpu.cfs_quota_us'), str(quota))
        else:
            _write(os.path.join(self.parent, 'cgroup.subtree_control'),
                   '+cpu +memory' if self.memory_mb else '+cpu')
            _write(os.path.join(self.path, 'cpu.max'), '%d %d' % (quota, self.period_us))
        if self.memory_mb:
            limit = str(int(self.memory_mb * 2 ** 20))
            if self.memory_path:
                os.makedirs(self.memory_path, exist_ok=True)
                _write(os.path.join(self.memory_path, 'memory.limit_in_bytes'), limit)
            else:
                _write(os.path.join(self.path, 'memory.max'), limit)
        return self

    def join(self, pid=None):
        """Put the calling process (or ``pid``, with its threads) in the group (a
        ``preexec_fn``: the child joins before it runs the host's command)."""
        pid = str(pid or os.getpid())
        _write(os.path.join(self.path, 'cgroup.procs'), pid)
        if self.memory_path:
            _write(os.path.join(self.memory_path, 'cgroup.procs'), pid)

    def pids(self):
        return _pids(self.path)

    def stats(self):
        """The controller's counts (``nr_periods``, ``nr_throttled``, throttled time ...)."""
        try:
            with open(os.path.join(self.path, 'cpu.stat')) as stream:
                return dict((k, int(v)) for k, v in (line.split() for line in stream
                                                     if len(line.split()) == 2))
        except OSError:
            return {}

    def remove(self):
        """Remove the group (its processes, if any are left, go back to the root)."""
        remove(self.path)
        if self.memory_path:
            remove(self.memory_path)


def remove(path):
    root = os.path.dirname(os.path.dirname(path))
    for pid in _pids(path):
        try:
            _write(os.path.join(root, 'cgroup.procs'), str(pid))
        except OSError:
            pass
    try:
        os.rmdir(path)
    except OSError as error:
        if error.errno != errno.ENOENT:
            raise


def _pids(path):
    try:
        with open(os.path.join(path, 'cgroup.procs')) as stream:
            return [int(p) for p in stream.read().split()]
    except OSError:
        return []


def limits(hosts, prefix):
    """``{host name: CpuLimit}`` of the hosts (scenario Hosts) that have a ``cpu`` share."""
    return dict((h.name, CpuLimit('%s-%s' % (prefix, h.name), h.cpu,
                                  int(round(h.cpu_period * 1e3)), h.memory))
                for h in hosts if h.cpu is not None)


def cleanup(prefix):
    """Remove the groups of a run with ``prefix``; returns their paths."""
    found = leftovers(prefix)
    for path in found:
        remove(path)
    return found


def leftovers(prefix):
    """Paths of the groups a run with ``prefix`` created that still exist."""
    try:
        roots = [controller()[1], MEMORY_V1]
    except EmulatorError:
        return []
    found = []
    for root in roots:
        parent = os.path.join(root, GROUP)
        try:
            names = os.listdir(parent)
        except OSError:
            continue
        found += [os.path.join(parent, n) for n in names if n.startswith(prefix + '-')]
    return found
