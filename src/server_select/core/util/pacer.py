"""Threads that wake when there is something to do, not on a fixed tick (no rospy).

A timer that polls (``rospy.Timer`` at 50 Hz to look for a passed deadline) costs a
thread wake-up each time whether or not anything is due; on a small robot that is most
of what a quiet node spends (bench-robot). A :class:`Pacer` runs ``act()`` when
``next_time()`` comes and sleeps until then; whoever changes what is due calls
:meth:`~Pacer.poke`. A :class:`Watchdog` runs a callback at a deadline unless it was
cancelled first: one thread for every deadline of a node (a ``threading.Timer`` starts a
thread per deadline).
"""

import heapq
import itertools
import threading
import time


class Pacer(object):
    """One thread that calls ``act()`` when ``next_time()`` (a ``clock`` time; None:
    not until poked) has come, and at once after :meth:`poke`. ``next_time`` is asked
    outside the pacer's lock, so it may take its owner's locks; an exception from ``act``
    goes to ``on_error`` and the pacer goes on. Two calls of ``act`` are at least
    ``floor`` s apart (a ``next_time`` that does not move on cannot make it spin)."""

    def __init__(self, act, next_time, clock=time.monotonic, name='pacer', floor=0.001,
                 on_error=None):
        self._act, self._next_time, self._clock = act, next_time, clock
        self._floor, self._on_error = floor, on_error or (lambda error: None)
        self._cond = threading.Condition()
        self._poked = self._stopped = False
        self.acts = 0
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def start(self):
        self._thread.start()
        return self

    def poke(self):
        """Something changed: ask ``next_time`` again now."""
        with self._cond:
            self._poked = True
            self._cond.notify()

    def stop(self, timeout=1.0):
        with self._cond:
            self._stopped = True
            self._cond.notify()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout)

    def _wait(self):
        """Sleep until the next time or a poke; False once stopped."""
        while True:
            when = self._next_time()
            with self._cond:
                if self._stopped:
                    return False
                if self._poked:
                    self._poked = False
                    return True
                delay = None if when is None else when - self._clock()
                if delay is not None and delay <= 0:
                    return True
                self._cond.wait(delay)
                if self._stopped:
                    return False
                if self._poked or (when is not None and self._clock() >= when):
                    self._poked = False
                    return True

    def _run(self):
        last = None
        while self._wait():
            now = self._clock()
            if last is not None and now - last < self._floor:
                time.sleep(self._floor - (now - last))
            last = self._clock()
            self.acts += 1
            try:
                self._act()
            except Exception as error:   # the owner's bug must not stop its pacing
                self._on_error(error)


class Watchdog(object):
    """Calls ``callback()`` at ``clock`` time ``deadline`` unless :meth:`cancel` came
    first; one thread for all (started with the first deadline)."""

    def __init__(self, clock=time.monotonic, name='watchdog'):
        self._clock, self._name = clock, name
        self._cond = threading.Condition()
        self._heap = []
        self._ids = itertools.count()
        self._armed = set()         # handles neither run nor cancelled
        self._thread = None

    def arm(self, seconds, callback):
        """Run ``callback`` in ``seconds`` s; returns a handle for :meth:`cancel`."""
        with self._cond:
            handle = next(self._ids)
            entry = (self._clock() + seconds, handle, callback)
            heapq.heappush(self._heap, entry)
            self._armed.add(handle)
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name=self._name, daemon=True)
                self._thread.start()
            elif self._heap[0] is entry:      # earlier than what the thread waits for
                self._cond.notify()
            return handle

    def cancel(self, handle):
        """The callback of ``handle`` will not run (if it has not yet)."""
        with self._cond:
            self._armed.discard(handle)

    def pending(self):
        """Deadlines armed and neither run nor cancelled."""
        with self._cond:
            return len(self._armed)

    def _run(self):
        while True:
            with self._cond:
                while self._heap and self._heap[0][1] not in self._armed:
                    heapq.heappop(self._heap)        # cancelled
                if not self._heap:
                    self._cond.wait()
                    continue
                delay = self._heap[0][0] - self._clock()
                if delay > 0:
                    self._cond.wait(delay)
                    continue
                _, handle, callback = heapq.heappop(self._heap)
                self._armed.discard(handle)
            try:
                callback()
            except Exception:     # a deadline's callback must not stop the others
                pass
