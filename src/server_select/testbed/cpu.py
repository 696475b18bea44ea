"""Real CPU capacity for testbed hosts: a cgroup with a CPU quota (no rospy).

A scenario host with ``cpu: 0.25`` gets a cgroup ``server_select/<prefix>-<host>`` whose
quota is a quarter of one core (``cpu.cfs_quota_us`` / ``cpu.cfs_period_us`` with the
cgroup v1 ``cpu`` controller, ``cpu.max`` with cgroup v2); every process the testbed starts
in the host joins it before it runs, and whatever it starts later inherits it. Its work
is then really slower: no sleep pretends to be work. Needs root.
"""

import errno
import os

from server_select.testbed.linkemu import EmulatorError

V1 = '/sys/fs/cgroup/cpu'
V2 = '/sys/fs/cgroup'
GROUP = 'server_select'
PERIOD_US = 100000


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
    """One host's cgroup: ``share`` of one core (0.25: a quarter; 2: two cores)."""

    def __init__(self, name, share):
        if not share >= 0.01:
            raise ValueError('a CPU share must be at least 0.01 of a core, got %r' % (share,))
        self.name, self.share = name, float(share)
        self.version, root = controller()
        self.parent = os.path.join(root, GROUP)
        self.path = os.path.join(self.parent, name)

    def create(self):
        if self.version == 'v2':      # the cpu controller must be on down to our groups
            _write(os.path.join(V2, 'cgroup.subtree_control'), '+cpu')
        os.makedirs(self.path, exist_ok=True)
        quota = int(round(self.share * PERIOD_US))
        if self.version == 'v1':
            _write(os.path.join(self.path, 'cpu.cfs_period_us'), str(PERIOD_US))
            _write(os.path.join(self.path, 'cpu.cfs_quota_us'), str(quota))
        else:
            _write(os.path.join(self.parent, 'cgroup.subtree_control'), '+cpu')
            _write(os.path.join(self.path, 'cpu.max'), '%d %d' % (quota, PERIOD_US))
        return self

    def join(self):
        """Put the calling process in the group (a ``preexec_fn``: the child joins before
        it runs the host's command)."""
        _write(os.path.join(self.path, 'cgroup.procs'), str(os.getpid()))

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
    return dict((h.name, CpuLimit('%s-%s' % (prefix, h.name), h.cpu))
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
        root = controller()[1]
    except EmulatorError:
        return []
    parent = os.path.join(root, GROUP)
    try:
        names = os.listdir(parent)
    except OSError:
        return []
    return [os.path.join(parent, n) for n in names if n.startswith(prefix + '-')]
