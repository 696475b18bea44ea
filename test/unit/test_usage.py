import os
import signal
import subprocess
import sys
import time

from server_select.core.util.procs import measure, stopped, wait_until


def busy(seconds):
    end = time.process_time() + seconds
    while time.process_time() < end:
        pass


def test_busy_process_shows_cpu_and_memory():
    # the window measured on this process's own CPU clock: whatever else the host runs,
    # the CPU time measure() reads for it equals the window (to the kernel's 10 ms ticks)
    usage = measure([os.getpid()], 0.3, clock=time.process_time, sleep=busy)
    me = usage[os.getpid()]
    assert 80.0 < me['cpu_percent'] < 120.0
    assert me['rss_mb'] > 1.0 and me['threads'] >= 1


def test_idle_process_shows_little_cpu_and_missing_pids_are_skipped():
    usage = measure([os.getpid(), 2 ** 22 + 12345], 0.3)
    assert list(usage) == [os.getpid()]
    assert usage[os.getpid()]['cpu_percent'] < 20.0


def test_stopped_says_when_a_sigstop_has_taken_effect_in_every_thread():
    code = 'import threading, time\nthreading.Thread(target=time.sleep, args=(30,)).start()\n' \
        'time.sleep(30)'
    proc = subprocess.Popen([sys.executable, '-c', code])
    try:
        assert wait_until(lambda: len(os.listdir('/proc/%d/task' % proc.pid)) == 2, 10.0)
        assert not stopped(proc.pid)
        os.kill(proc.pid, signal.SIGSTOP)
        assert wait_until(lambda: stopped(proc.pid), 5.0)
        os.kill(proc.pid, signal.SIGCONT)
        assert wait_until(lambda: not stopped(proc.pid), 5.0)
    finally:
        proc.kill()
        proc.wait()
    assert not stopped(proc.pid)           # gone
