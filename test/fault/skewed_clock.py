#!/usr/bin/env python3
"""A robot node whose wall clock is SKEW s off this host's (a Pi without a real-time clock
that booted with a wrong time) until it gets SIGUSR1: then its clock is stepped to this
host's, as NTP steps a clock it corrects. Its monotonic clock runs true throughout.

    skewed_clock.py SKEW [ROBOT ARGS]
"""

import signal
import sys
import time

_OFFSET_NS = [int(float(sys.argv[1]) * 1e9)]
_TIME, _TIME_NS = time.time, time.time_ns


def _stepped(_signum, _frame):
    _OFFSET_NS[0] = 0


# before anything reads the clock, or keeps time.time as a default argument
time.time = lambda: _TIME() + _OFFSET_NS[0] * 1e-9
time.time_ns = lambda: _TIME_NS() + _OFFSET_NS[0]
signal.signal(signal.SIGUSR1, _stepped)
sys.argv = ['robot'] + sys.argv[2:]

from server_select.nodes.robot import main  # noqa: E402

main()
