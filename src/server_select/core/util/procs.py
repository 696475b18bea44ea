"""Processes: waiting for a condition, stopping a process group or a set of processes, CPU
and memory use."""

import math
import os
import signal
import subprocess
import time

import psutil


def wait_until(condition, timeout, period=0.05, clock=time.monotonic, sleep=time.sleep):
    """Poll ``condition()`` every ``period`` s until it is true (True) or ``timeout`` passes
    (then the last answer of ``condition()``)."""
    deadline = clock() + timeout
    while clock() < deadline:
        if condition():
            return True
        sleep(period)
    return bool(condition())


def stop_group(proc, sig=signal.SIGINT, timeout=15.0):
    """Stop a ``Popen`` started with ``start_new_session=True``, with its whole process
    group: ``sig`` first, SIGKILL after ``timeout`` s. Returns the exit status."""
    return stop_groups([proc], sig, timeout)[0]


def stop_groups(procs, sig=signal.SIGINT, timeout=15.0, clock=time.monotonic):
    """:func:`stop_group` for several at once: ``sig`` to every group, then each is waited
    for until ``timeout`` s from then, and SIGKILLed if still there. Their exit statuses."""
    procs = list(procs)
    for proc in procs:
        if proc.poll() is None:
            try:
                os.killpg(proc.pid, sig)
            except ProcessLookupError:
                pass
    deadline = clock() + timeout
    statuses = []
    for proc in procs:
        try:
            statuses.append(proc.wait(max(0.0, deadline - clock())))
        except subprocess.TimeoutExpired:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            statuses.append(proc.wait())
    return statuses


def usable_cpus(pid='self', root='/sys/fs/cgroup'):
    """The cores process ``pid`` may use: its CPU affinity, capped by its cgroup's CPU quota
    (v1 ``cpu.cfs_quota_us`` / ``cpu.cfs_period_us``, v2 ``cpu.max``), rounded up (a
    quarter of a core is one)."""
    cores = len(os.sched_getaffinity(0 if pid == 'self' else int(pid)))
    try:
        with open('/proc/%s/cgroup' % pid) as stream:
            lines = [line.rstrip('\n').split(':', 2) for line in stream]
    except OSError:
        return cores
    for _, controllers, path in lines:
        quota = None
        if 'cpu' in controllers.split(','):
            quota = _read(os.path.join(root, 'cpu', path.lstrip('/'), 'cpu.cfs_quota_us'),
                          os.path.join(root, 'cpu', path.lstrip('/'), 'cpu.cfs_period_us'))
        elif controllers == '':
            quota = _read(os.path.join(root, path.lstrip('/'), 'cpu.max'))
        if quota:
            cores = min(cores, max(1, int(math.ceil(quota - 1e-9))))
    return cores


def _read(path, period_path=None):
    """A quota in cores from ``cpu.max`` (``quota period``) or from a v1 quota file and its
    period's; None: no limit, or no such file."""
    try:
        with open(path) as stream:
            words = stream.read().split()
        if period_path is not None:
            with open(period_path) as stream:
                words.append(stream.read().strip())
    except OSError:
        return None
    if len(words) != 2 or words[0] in ('max', '-1'):
        return None
    return int(words[0]) / float(words[1])


def kill_all(pids, grace=5.0):
    """SIGTERM, then SIGKILL what is left after ``grace`` seconds."""
    for pid in pids:
        try:
            os.kill(pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
    wait_until(lambda: not any(alive(p) for p in pids), grace)
    for pid in pids:
        if alive(pid):
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


def stat_fields(path):
    """The fields of a ``/proc/.../stat`` file after the command name (which may hold
    spaces and parentheses): ``[0]`` the state, ``[11]`` and ``[12]`` user and system
    ticks, ``[19]`` the start time. OSError when the process is gone."""
    with open(path) as stream:
        return stream.read().rsplit(')', 1)[1].split()


def alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:  # a zombie child counts as gone
        return stat_fields('/proc/%d/stat' % pid)[0] != 'Z'
    except OSError:
        return False


def stopped(pid):
    """Whether every thread of ``pid`` is stopped: a SIGSTOP takes effect when each
    thread next enters the kernel, so a request sent right after ``kill`` may still be
    answered."""
    try:
        for tid in os.listdir('/proc/%d/task' % pid):
            if stat_fields('/proc/%d/task/%s/stat' % (pid, tid))[0] not in ('T', 't'):
                return False
    except OSError:        # gone, or a thread gone between the listing and the read
        return False
    return True


def measure(pids, duration, clock=time.monotonic, sleep=time.sleep):
    """``{pid: {'cpu_percent', 'rss_mb', 'threads'}}`` over ``duration`` seconds.

    CPU% is (user + system) CPU time used during the window divided by the window length,
    so 100 means one core busy; RSS is sampled at the end. Processes that exit during
    the window are left out.
    """
    procs, before = {}, {}
    for pid in pids:
        try:
            proc = psutil.Process(pid)
            times = proc.cpu_times()
        except psutil.Error:
            continue
        procs[pid] = proc
        before[pid] = times.user + times.system
    start = clock()
    sleep(duration)
    elapsed = clock() - start
    usage = {}
    for pid, proc in procs.items():
        try:
            with proc.oneshot():
                times = proc.cpu_times()
                rss = proc.memory_info().rss
                threads = proc.num_threads()
        except psutil.Error:
            continue
        usage[pid] = {
            'cpu_percent': 100.0 * (times.user + times.system - before[pid]) / elapsed,
            'rss_mb': rss / 2.0 ** 20,
            'threads': threads,
        }
    return usage


def epoll_descriptors(pid='self'):
    """How many epoll descriptors process ``pid`` holds (rospy makes one per topic)."""
    def target(fd):
        try:
            return os.readlink('/proc/%s/fd/%s' % (pid, fd))
        except OSError:
            return ''
    return sum('eventpoll' in target(fd) for fd in os.listdir('/proc/%s/fd' % pid))
