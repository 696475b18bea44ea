"""A probe still out is late by TCP's retransmission timeout over the server's answers."""

import pytest

from server_select.core.selection.answer_time import AnswerTimes


def test_a_server_without_answers_is_late_at_once():
    times = AnswerTimes()
    assert times.limit(1) is None
    assert times.late(1, 0.0)


def test_the_estimate_follows_rfc_6298():
    times = AnswerTimes()
    times.answered(1, 0.010)                    # SRTT = R, RTTVAR = R / 2
    assert times.limit(1) == pytest.approx(0.010 + 4 * 0.005)
    times.answered(1, 0.030)                    # RTTVAR first, from the old SRTT
    rttvar = 0.75 * 0.005 + 0.25 * 0.020
    srtt = 0.875 * 0.010 + 0.125 * 0.030
    assert times.limit(1) == pytest.approx(srtt + 4 * rttvar)


def test_a_steady_fast_server_is_late_soon_and_a_busy_capped_one_is_given_its_time():
    times = AnswerTimes()
    for _ in range(40):
        times.answered('steady', 0.010)
    for rtt in [0.05, 0.30, 0.08, 0.25, 0.04, 0.20] * 6:   # a busy server on 10 % of a core
        times.answered('capped', rtt)
    assert times.late('steady', 0.1)           # hung: late by the next probe, 0.1 s on
    assert not times.late('capped', 0.3)       # slow as it has been: not late
    assert times.late('capped', 0.8)


def test_a_forgotten_server_starts_again():
    times = AnswerTimes()
    times.answered(2, 0.5)
    times.forget(2)
    assert times.late(2, 0.2)
