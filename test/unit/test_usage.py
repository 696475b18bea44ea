import os
import time

from server_select.core.util.procs import measure


def busy(seconds):
    end = time.process_time() + seconds
    while time.process_time() < end:
        pass


def test_busy_process_shows_cpu_and_memory():
    usage = measure([os.getpid()], 0.3, sleep=busy)
    me = usage[os.getpid()]
    assert me['cpu_percent'] > 50.0
    assert me['rss_mb'] > 1.0 and me['threads'] >= 1


def test_idle_process_shows_little_cpu_and_missing_pids_are_skipped():
    usage = measure([os.getpid(), 2 ** 22 + 12345], 0.3)
    assert list(usage) == [os.getpid()]
    assert usage[os.getpid()]['cpu_percent'] < 20.0
