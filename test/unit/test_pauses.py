"""Pauses: a task timed across a stop of its process is known as such, others are not."""

import pytest

from server_select.core.load.pauses import Pauses


class Clock(object):
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def ticking(clock, pauses, until):
    """The ticker's beats, every tick s, up to ``until``."""
    while clock.now + pauses.tick_seconds <= until:
        clock.now += pauses.tick_seconds
        pauses.tick()


def test_pauses_a_task_timed_while_the_ticker_beats_is_work():
    clock = Clock()
    pauses = Pauses(least=1.0, tick=0.2, clock=clock)
    start = clock.now
    ticking(clock, pauses, start + 3.0)
    assert not pauses.across(start, clock.now)


def test_pauses_a_task_timed_across_a_stop_the_ticker_saw_is_not_work():
    clock = Clock()
    pauses = Pauses(least=1.0, tick=0.2, clock=clock)
    ticking(clock, pauses, 101.0)
    start = clock.now - 0.1               # a frame begun just before the stop
    clock.now += 5.0                      # SIGSTOP ... SIGCONT: nothing ran
    assert pauses.tick() == pytest.approx(5.0)
    ticking(clock, pauses, clock.now + 0.5)
    assert pauses.across(start, clock.now)
    # the tasks begun after it, and those done before it, are work
    assert not pauses.across(clock.now - 0.3, clock.now)
    assert not pauses.across(100.2, 100.6)


def test_pauses_a_task_ending_before_the_ticker_ran_again_sees_the_tick_overdue():
    clock = Clock()
    pauses = Pauses(least=1.0, tick=0.2, clock=clock)
    ticking(clock, pauses, 101.0)
    start = clock.now
    clock.now += 4.0                      # the worker wakes first after the stop
    assert pauses.across(start, clock.now)


def test_pauses_a_late_tick_under_the_bound_is_no_pause():
    clock = Clock()
    pauses = Pauses(least=1.0, tick=0.2, clock=clock)
    start = clock.now
    clock.now += 0.9                      # a starved ticker, late but under the bound
    assert pauses.tick() == 0.0
    assert not pauses.across(start, clock.now)


def test_pauses_keeps_a_bounded_history():
    clock = Clock()
    pauses = Pauses(least=1.0, tick=0.2, keep=3, clock=clock)
    for _ in range(10):
        clock.now += 2.0
        pauses.tick()
    assert len(pauses._gaps) == 3
    assert not pauses.across(100.5, 101.5)    # forgotten: tasks are not that long
    with pytest.raises(ValueError):
        Pauses(least=0.2, tick=0.2)


def test_pauses_run_ticks_until_stopped():
    clock = Clock()
    pauses = Pauses(least=1.0, tick=0.2, clock=clock)
    beats = []

    def sleep(seconds):
        beats.append(seconds)
        clock.now += 3.0 if len(beats) == 2 else seconds

    pauses.run(stopped=lambda: len(beats) >= 4, sleep=sleep)
    assert beats == [0.2] * 4
    assert len(pauses._gaps) == 1
