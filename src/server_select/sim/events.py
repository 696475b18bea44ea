"""A discrete-event loop on a virtual clock, and seeded random streams (no rospy).

Why a heap and not SimPy: the core objects the simulator drives are callbacks that say
when they next have something to do (``TaskFlow.next_wake``, ``ProbePlan.next_time``), not
processes that wait; a heap of timed callbacks is all the loop needs, costs no dependency,
and runs a few times faster than a generator per process.

Paired seeds (common random numbers): every random draw comes from a stream named by what
it is for (a link's direction, a robot's tasks, a rule's draws), seeded from the run's seed
and that name, so two variants run with one seed see the same jitter, losses and task
sizes even where their decisions differ.
"""

import heapq
import itertools
import random


class EventLoop(object):
    """Callbacks at virtual times; :meth:`now` is the clock every core object is given."""

    def __init__(self, start=0.0):
        self._now = float(start)
        self._heap = []
        self._order = itertools.count()     # ties run in the order they were scheduled
        self.events = 0

    def now(self):
        return self._now

    def at(self, when, callback, *args):
        """Run ``callback(*args)`` at ``when`` (not before now)."""
        heapq.heappush(self._heap, (max(when, self._now), next(self._order), callback, args))

    def after(self, delay, callback, *args):
        self.at(self._now + delay, callback, *args)

    def run(self, until):
        """Run every event up to ``until`` (s); the clock ends there."""
        heap = self._heap
        while heap and heap[0][0] <= until:
            when, _, callback, args = heapq.heappop(heap)
            self._now = when
            self.events += 1
            callback(*args)
        self._now = max(self._now, until)


class Wakeup(object):
    """One pending call of ``callback`` at the earliest time asked for (a timer that
    only moves earlier until it fires): what a node's pacing thread does."""

    def __init__(self, loop, callback):
        self.loop, self.callback = loop, callback
        self.when = None
        self._generation = 0

    def request(self, when):
        if when is None or (self.when is not None and self.when <= when):
            return
        self.when = when
        self._generation += 1
        self.loop.at(when, self._fire, self._generation)

    def _fire(self, generation):
        if generation != self._generation:
            return            # replaced by an earlier request that has fired
        self.when = None
        self.callback()


class Streams(object):
    """Independent random sources named by purpose, all from one ``seed``."""

    def __init__(self, seed):
        self.seed = seed
        self._streams = {}      # 'a/b' -> its stream
        self._named = {}        # ('a', 'b') -> the same

    def rng(self, *name):
        stream = self._named.get(name)      # (asked per message: no string built then)
        if stream is None:
            key = '/'.join(str(part) for part in name)
            stream = self._streams.get(key)
            if stream is None:
                stream = self._streams[key] = random.Random('%s/%s' % (self.seed, key))
            self._named[name] = stream
        return stream
