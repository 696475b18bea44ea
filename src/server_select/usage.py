"""CPU and memory use of processes over a time window, read from /proc via psutil."""

import time

import psutil


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
