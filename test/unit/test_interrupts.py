"""A signal that arrives while a node is still importing is kept, not lost."""

import os
import signal

from server_select.core.util import interrupts


def test_a_signal_before_rospy_starts_is_kept():
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        interrupts.hold()
        os.kill(os.getpid(), signal.SIGINT)
        os.kill(os.getpid(), signal.SIGTERM)
        assert interrupts.held() == [signal.SIGINT, signal.SIGTERM]
    finally:
        for signum, handler in before.items():
            signal.signal(signum, handler)
        del interrupts._HELD[:]
