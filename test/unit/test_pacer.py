"""Pacer and Watchdog: threads that wake when something is due, and only then."""

import threading
import time

from server_select.core.util.pacer import Pacer, Watchdog
from server_select.core.util.procs import wait_until


def test_a_pacer_acts_when_its_time_comes_and_sleeps_otherwise():
    start = time.monotonic()
    times = [start + 0.05, start + 0.10]
    acted = []

    def act():
        acted.append(time.monotonic())
        if times:
            times.pop(0)
    pacer = Pacer(act, lambda: times[0] if times else None).start()
    try:
        assert wait_until(lambda: len(acted) == 2, 2.0)
        time.sleep(0.2)                       # nothing due: no more acts
        assert len(acted) == 2 and pacer.acts == 2
        assert acted[0] - start >= 0.05 - 1e-3 and acted[1] - start >= 0.10 - 1e-3
    finally:
        pacer.stop()


def test_a_poke_makes_it_act_at_once_and_an_error_does_not_stop_it():
    acted, errors = [], []

    def act():
        acted.append(1)
        if len(acted) == 1:
            raise RuntimeError('owner bug')
    pacer = Pacer(act, lambda: None, on_error=errors.append).start()
    try:
        time.sleep(0.05)
        assert acted == []                    # never due by itself
        pacer.poke()
        assert wait_until(lambda: len(acted) == 1, 1.0)
        pacer.poke()
        assert wait_until(lambda: len(acted) == 2, 1.0)
        assert [str(e) for e in errors] == ['owner bug']
    finally:
        pacer.stop()
    assert not pacer._thread.is_alive()


def test_a_next_time_that_never_moves_on_is_bounded_by_the_floor():
    start = time.monotonic()
    pacer = Pacer(lambda: None, lambda: 0.0, floor=0.01).start()
    time.sleep(0.2)
    pacer.stop()
    elapsed = time.monotonic() - start
    assert 1 <= pacer.acts <= elapsed / 0.01 + 1, (pacer.acts, elapsed)


def test_a_watchdog_runs_what_is_not_cancelled_in_deadline_order():
    dog = Watchdog()
    ran, lock = [], threading.Lock()

    def note(name):
        def run():
            with lock:
                ran.append(name)
        return run
    late = dog.arm(0.15, note('late'))
    dog.arm(0.10, note('middle'))
    early = dog.arm(0.02, note('early'))          # earlier than what the thread waits for
    cancelled = dog.arm(0.05, note('cancelled'))
    dog.cancel(cancelled)
    assert dog.pending() == 3
    assert wait_until(lambda: len(ran) == 3, 2.0)
    time.sleep(0.1)
    assert ran == ['early', 'middle', 'late'] and dog.pending() == 0
    dog.cancel(late)                              # after it ran: nothing happens
    dog.cancel(early)
    assert dog.pending() == 0 and threading.active_count() < 50
