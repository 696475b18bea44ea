"""How long a condition has held, per key: :class:`Lasting` says when it has held for a
grace period (then its count starts again), so a repair that the condition calls for is
tried once per grace period, never at every look."""

import time


class Lasting(object):
    """``held(key, now_true)``: whether the condition of ``key`` has been true at every
    look for ``grace`` s (a false look forgets it). Bounded by the keys the caller keeps:
    :meth:`forget` drops one."""

    def __init__(self, grace, clock=time.monotonic):
        self.grace, self._clock = grace, clock
        self._since = {}            # key -> when the condition was first seen true

    def held(self, key, now_true):
        if not now_true:
            self._since.pop(key, None)
            return False
        now = self._clock()
        since = self._since.setdefault(key, now)
        if now - since < self.grace:
            return False
        self._since[key] = now      # the next repair after another grace period
        return True

    def forget(self, key):
        self._since.pop(key, None)
