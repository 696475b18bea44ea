"""A probe still out is late once older than twice the server's longest recent answer."""

from server_select.core.robot.answer_time import KEEP, AnswerTimes


def test_a_server_without_answers_is_late_at_once():
    times = AnswerTimes()
    assert times.limit(1) is None
    assert times.late(1, 0.0)


def test_a_steady_server_is_late_by_the_next_probe_and_a_busy_capped_one_is_not():
    times = AnswerTimes()
    for rtt in [0.010, 0.012, 0.025, 0.011] * 10:
        times.answered('steady', rtt)
    # a capped server's answers as measured at 2x overload: fast when its worker is idle
    for rtt in [0.004, 0.004, 0.005, 0.054, 0.154, 0.004, 0.258, 0.328, 0.004, 0.1] * 4:
        times.answered('capped', rtt)
    assert times.limit('steady') == 0.050
    assert times.late('steady', 0.1)          # a link down: late by the next 10 Hz probe
    assert times.limit('capped') == 0.656
    assert not times.late('capped', 0.4)      # answering as slowly as it has been
    assert times.late('capped', 0.7)


def test_only_the_last_answers_count():
    times = AnswerTimes()
    times.answered(1, 0.4)
    for _ in range(KEEP):
        times.answered(1, 0.01)
    assert times.limit(1) == 0.02


def test_a_forgotten_server_starts_again():
    times = AnswerTimes()
    times.answered(2, 0.5)
    times.forget(2)
    assert times.late(2, 0.2)
