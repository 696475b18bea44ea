"""A server's load: its bounded work queue, and what a robot makes of its reports (no rospy).

A task's round trip is the network, the wait for a worker and the work; a probe, answered
on its own thread, measures only the first. So every probe answer carries the server's
:class:`Load`: tasks queued and in service, workers, the *backlog* (seconds a task sent now
would wait for a worker), the *utilization* (the share of the workers' time the other
robots' tasks take: what they *announce*, :mod:`server_select.core.load.demand`; it moves
only when a robot comes, goes or changes its rate, where the backlog follows the phase of
each other's frames, which robots that ranked by it chased) and the recent work per task of
each kind, which a robot ranks by with the round trip and the wait (C3's expected
completion, NSDI '15; :mod:`server_select.core.rule.estimates`).

Server side, :class:`WorkQueue` holds the tasks waiting for the workers, each with its
*deadline* (refused at once as busy when it cannot be met; shed when it passes while the
task waits), shared fairly between the robots
(:class:`~server_select.core.load.fair_queue.FairQueue`).
"""

import collections
import threading
import time

from server_select.core.load.demand import Demand
from server_select.core.load.fair_queue import FairQueue, Job
from server_select.core.load.service_times import SenderShares, ServiceTimes

CHECK = 'check'     # the owner of a check's job (:meth:`WorkQueue.offer_check`): no robot
Load = collections.namedtuple('Load', 'queued in_service workers backlog service utilization '
                              'service_error')
Load.__new__.__defaults__ = (0.0, None)
Load.__doc__ = """One load report: ``service`` is ``{kind: seconds of work per task}``,
``utilization`` the share of the workers' time the others' tasks take (0: none),
``service_error`` ``{kind: the standard error of that work}`` (None: not reported)."""


class WorkQueue(object):
    """Tasks waiting for ``workers`` workers, at most ``max_queue`` of them holding at most
    ``max_bytes`` (None: any; a task alone is taken whatever its size) (thread-safe): one
    pushed out by a newer task of a robot holding less of the queue goes to
    ``on_pushed_out(job, why)`` (answered busy). Robots' rates are announced (kept
    ``announce_age`` s), else counted as their tasks arrive (over ``horizon`` s).
    """

    def __init__(self, workers, max_queue, times=None, clock=time.monotonic, horizon=10.0,
                 announce_age=3.0, max_bytes=None, on_pushed_out=None):
        if workers < 1 or max_queue < 1:
            raise ValueError('workers and max_queue must be >= 1, got %r, %r'
                             % (workers, max_queue))
        self.workers, self.max_queue = int(workers), int(max_queue)
        self.max_bytes, self.on_pushed_out = max_bytes, on_pushed_out
        self.times = times or ServiceTimes(clock=clock)
        self.demand = Demand(horizon, announce_age)
        self._clock, self._cond = clock, threading.Condition()
        self._queue = FairQueue()
        self._shares = SenderShares()     # each robot's share of its kind's usual work
        self._running, self._closed = set(), False
        self.refused = self.shed = self.finished = self.pushed_out = 0

    @property
    def queued_bytes(self):
        return self._queue.bytes

    def _backlog(self, now, excluding=None):
        """Seconds until a worker is free for one more task, ``excluding``'s left out."""
        if len(self._queue) + len(self._running) < self.workers:
            return 0.0           # a worker is free, whoever's tasks are left out
        queued = [job for job in self._queue.jobs()
                  if excluding is None or job.owner != excluding]
        running = [job for job in self._running if excluding is None or job.owner != excluding]
        if len(running) + len(queued) < self.workers:
            return 0.0
        work = sum(self._job_work(job, now) for job in queued)
        return (work + self._left(running, now)) / self.workers

    def _left(self, running, now):
        """Seconds of work the ``running`` jobs have left (lock held)."""
        return sum(max(0.0, self._job_work(job, now) - (now - job.started))
                   for job in running)

    def _job_work(self, job, now, owner=None, kind=None):
        """Seconds of work of ``job`` (or of a task of ``owner`` and ``kind``; lock held):
        its kind's, times its robot's share of it (:class:`SenderShares`)."""
        owner, kind = (owner, kind) if job is None else (job.owner, job.kind)
        return self._work(kind, now) * self._shares.ratio(owner, kind)

    def _work(self, kind, now):
        """Seconds of work per ``kind`` task (lock held): the recent median, or while none is
        known its longest-running task's so far (a server's first frames, which load what
        the kind needs, once counted as none, drew every robot)."""
        known = self.times.get(kind, None)
        if known is not None:
            return known
        return max([now - job.started for job in self._running if job.kind == kind] or [0.0])

    def offer(self, kind, item, deadline=None, owner=None, size=0):
        """Queue ``item`` (a task of ``kind`` wanted by ``deadline``, None: whenever, sent
        by ``owner``, holding ``size`` bytes): None when queued, else why it was refused."""
        with self._cond:
            now = self._clock()
            room = None if self._closed else self._queue.room_for(
                owner, size, self.max_queue, self.max_bytes)
            why = self._refusal(kind, owner, size, deadline, now, room)
            if why is not None:
                self.refused += 1
                return why
            self._queue.push_out(room)
            self.pushed_out += len(room)
            self._queue.push(Job(kind, item, deadline, now, owner, size))
            self.demand.arrived(owner, kind, now)
            self._cond.notify()
        for job in room:
            if self.on_pushed_out is not None:
                self.on_pushed_out(job, 'busy: pushed out of the queue by a task of a robot '
                                   'holding less of it')
        return None

    def offer_check(self, every, item_of):
        """While nobody sends here and no worker is busy, a check of a kind due one
        (:meth:`ServiceTimes.due`): a job of :data:`CHECK` holding ``item_of(kind)`` (None:
        not checked), timed as a task's (:meth:`done`). The kind queued, or None."""
        with self._cond:      # (off, asked at every probe: declined before the rates)
            now = self._clock()
            if every <= 0 or self._closed or self._running or self._queue or self.demand.rates(now):
                return None
            for kind in self.times.due(every):
                item = item_of(kind)
                if item is not None:
                    self.times.checking(kind)
                    self._queue.push(Job(kind, item, None, now, CHECK))
                    self._cond.notify()
                    return kind
        return None

    def _refusal(self, kind, owner, size, deadline, now, room):
        """Why a task is not queued, or None (lock held)."""
        if self._closed:
            return 'the server is shutting down'
        if room is None and len(self._queue) >= self.max_queue:
            return 'busy: %d tasks queued already' % len(self._queue)
        if room is None:
            return 'busy: the tasks queued hold %d bytes; %d more is over %d' % (
                self._queue.bytes, size, self.max_bytes)
        if deadline is not None:
            cost = self._job_work(None, now, owner, kind)
            finish = self._wait(owner, cost, now, room) + cost
            if now + finish > deadline:
                return 'busy: would finish in %.3g s, its deadline is in %.3g s' % (
                    finish, max(0.0, deadline - now))
        return None

    def _wait(self, owner, cost, now, leaving=()):
        """Seconds until a worker takes one more task of ``owner`` (lock held): what the
        running tasks have left, and the queued work the round robin serves before it
        (:meth:`FairQueue.wait_work`; ``leaving``: jobs about to be pushed out)."""
        if len(self._running) + len(self._queue) - len(leaving) < self.workers:
            return 0.0
        gone = set(map(id, leaving))

        def work(job):
            return 0.0 if id(job) in gone else self._job_work(job, now)
        return (self._left(self._running, now)
                + self._queue.wait_work(owner, cost, work)) / self.workers

    def take(self, wait=True):
        """The next job by the robots' round robin that a worker may take (:meth:`_may_take`),
        once there is one (``wait`` False: None at once if none); None once closed."""
        with self._cond:
            while not self._closed:
                now = self._clock()
                job = self._queue.pop(lambda queued: self._job_work(queued, now),
                                      self._may_take(now)) if len(self._queue) else None
                if job is not None:
                    job.started = now
                    # alone: none beside it so far, nor waiting (received on the CPU it shares)
                    job.alone = not self._running and not len(self._queue)
                    for other in self._running:       # nor, from now on, beside these
                        other.alone = False
                    self._running.add(job)
                    return job
                if not wait:
                    return None
                self._cond.wait()
            return None

    def _may_take(self, now):
        """Whose job a worker may take (None: anyone's; lock held): while others send here,
        no robot holds every worker (their tasks start at once, beside its long ones)."""
        if self.workers < 2:
            return None
        held = collections.Counter(job.owner for job in self._running)
        return lambda owner: held[owner] < self.workers - 1 or not self.demand.others(now, owner)

    def stale(self, job):
        """Why ``job`` (just taken) is not worth doing any more (its deadline would pass
        before its work is done), or None; a stale job counts as shed and is done."""
        if job.deadline is None:
            return None
        with self._cond:
            work = self._job_work(job, job.started)
            if job.started + work <= job.deadline:
                return None
            self._running.discard(job)
            self.shed += 1
            self._cond.notify_all()     # (a worker held back by :meth:`_may_take`)
        return 'busy: waited %.3g s in the queue; its deadline passed' % (
            job.started - job.queued_at)

    def done(self, job, seconds=None):
        """``job`` is finished; ``seconds`` of work (None: not a measure of the kind's
        work, e.g. a rejected task)."""
        with self._cond:
            self._running.discard(job)
            self.finished += job.owner != CHECK
            self._cond.notify_all()
            if seconds is not None and job.owner != CHECK:
                self._shares.add(job.owner, job.kind, seconds)
        if seconds is not None:
            self.times.add(job.kind, seconds, job.alone)

    def announce(self, owner, rates):
        """``owner`` sends ``(kind, tasks per second)`` pairs here now (none: nothing)."""
        with self._cond:
            self.demand.announce(owner, rates, self._clock())

    def _utilization(self, now, excluding):
        """The others' work per second over the workers (call with the lock held)."""
        return sum(rate * self._work(kind, now)
                   for kind, rate in self.demand.rates(now, excluding).items()) / self.workers

    def load(self, excluding=None):
        """The :class:`Load` now, its backlog and utilization without the tasks of owner
        ``excluding``: a robot that saw its own tasks as load on its server and none on
        the others would move for nothing (moving adds them to another's)."""
        with self._cond:
            now = self._clock()
            service = self.times.snapshot()
            for job in self._running:         # a kind not timed yet: its bound so far
                if job.kind not in service:
                    service[job.kind] = self._work(job.kind, now)
            return Load(len(self._queue), len(self._running), self.workers,
                        self._backlog(now, excluding), service,
                        self._utilization(now, excluding), self.times.errors())

    def close(self):
        """Wake every worker with None; what is still queued is dropped (returned)."""
        with self._cond:
            self._closed = True
            dropped = self._queue.clear()
            self._cond.notify_all()
            return dropped
