"""A server's load: its bounded work queue, and what a robot makes of its reports (no rospy).

A task's round trip is the network, the wait for a worker and the work itself. A probe,
answered on its own thread, measures only the first; so every probe answer carries the
server's :class:`Load` (tasks queued and in service, workers, the *backlog*: seconds a
task sent now would wait for a worker, the *utilization*: the share of the workers' time
the other robots' tasks take at the rates they announce, and the recent work per task of
each kind), and a robot ranks servers by round trip + expected wait + work for the tasks it
sends (C3's expected completion, NSDI '15; :mod:`server_select.core.load.board`).

The backlog is what a task sent now waits for: what an attempt's deadline follows. It is
also a poor forecast of the next task's wait: a server that does a frame in 0.7 s for two
robots is idle half the time and 0.7 s behind the other half, so robots that ranked by it
chased the phase of each other's frames. The utilization moves only when a robot comes,
goes or changes its rate. It is what the robots *announce*: a load-aware robot's probe
says the rate at which it sends tasks to that server now (its rate to the server its next
task goes to, none to the others), so a robot that moves loads its new server in the
others' eyes at its next probe, not after its tasks have arrived for a while (robots that
all saw an idle server came up idle moved to it together). The tasks of a robot that
announces nothing count at the rate they arrive (:mod:`server_select.core.load.demand`).

Server side, :class:`WorkQueue` holds the tasks waiting for the workers. A task carries
its *deadline* (when its robot stops waiting): one that cannot be finished by then is
refused at once (the robot hears "busy" and sends it elsewhere, or drops it for a newer
frame) instead of waiting in the queue for an answer nobody wants; one whose deadline
passes while it waits is shed when a worker takes it. The queue is shared fairly between
the robots (:class:`~server_select.core.load.fair_queue.FairQueue`): a task waits behind
about as much of each other robot's work as its own robot has queued, and one robot's
flood of tasks takes no place another robot's task needs.
"""

import collections
import threading
import time

from server_select.core.load.demand import Demand
from server_select.core.load.fair_queue import FairQueue, Job
from server_select.core.load.service_times import SenderShares, ServiceTimes

Load = collections.namedtuple('Load', 'queued in_service workers backlog service utilization '
                              'service_error')
Load.__new__.__defaults__ = (0.0, None)
Load.__doc__ = """One load report: ``service`` is ``{kind: seconds of work per task}``,
``utilization`` the share of the workers' time the others' tasks take (0: none),
``service_error`` ``{kind: the standard error of that work}`` (None: not reported)."""


class WorkQueue(object):
    """Tasks waiting for ``workers`` workers, at most ``max_queue`` of them holding at most
``max_bytes`` (None: any; a task alone in the queue is taken whatever its size)
(thread-safe).

    :meth:`offer` queues a task or says at once why not (full, or it cannot be done by its
    deadline: busy); a task that a newer one of a robot holding less of the queue pushes
    out is handed to ``on_pushed_out(job, why)`` (to be answered busy). Workers
    :meth:`take` the next by the round robin of the robots (None once closed), ask
    :meth:`stale` whether its deadline has passed meanwhile, and call :meth:`done` with the
    seconds it took, which teach :class:`ServiceTimes`. :meth:`announce` hears what a
    robot's probe says it sends here (:class:`~server_select.core.load.demand.Demand`: kept
    ``announce_age`` s; a robot that announces nothing counts by its arrivals over
    ``horizon`` s). Deadlines and times are those of ``clock``.
    """

    def __init__(self, workers, max_queue, times=None, clock=time.monotonic, horizon=10.0,
                 announce_age=3.0, max_bytes=None, on_pushed_out=None):
        if workers < 1 or max_queue < 1:
            raise ValueError('workers and max_queue must be >= 1, got %r, %r'
                             % (workers, max_queue))
        self.workers, self.max_queue = int(workers), int(max_queue)
        self.max_bytes = max_bytes
        self.on_pushed_out = on_pushed_out
        self.times = times or ServiceTimes(clock=clock)
        self.demand = Demand(horizon, announce_age)
        self._clock = clock
        self._cond = threading.Condition()
        self._queue = FairQueue()
        self._shares = SenderShares()     # each robot's share of its kind's usual work
        self._running = set()
        self._closed = False
        self.refused = self.shed = self.finished = self.pushed_out = 0

    @property
    def queued_bytes(self):
        return self._queue.bytes

    def _backlog(self, now, excluding=None):
        """Seconds until a worker is free for one more task (call with the lock held),
        leaving out the tasks of owner ``excluding`` (None: counting every task)."""
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
        """Seconds of work per ``kind`` task (lock held): the recent median; while none is
        known, as long as the longest-running task of the kind has taken so far. (A
        server's first frames, which also load what the kind needs, were taken for no
        work: every robot sent its frames to the first idle server, and gave them up
        there together.)"""
        known = self.times.get(kind, None)
        if known is not None:
            return known
        return max([now - job.started for job in self._running if job.kind == kind] or [0.0])

    def offer(self, kind, item, deadline=None, owner=None, size=0):
        """Queue ``item`` (a task of ``kind`` wanted by ``deadline``, None: whenever, sent
        by ``owner``, holding ``size`` bytes). Returns None when queued, else why it is
        refused (it was not queued)."""
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

    def take(self):
        """The next queued job by the robots' round robin, once there is one (blocks);
        None once closed."""
        with self._cond:
            while not len(self._queue) and not self._closed:
                self._cond.wait()
            if self._closed:
                return None
            now = self._clock()
            job = self._queue.pop(lambda queued: self._job_work(queued, now))
            job.started = now
            # alone: none beside it so far, nor waiting (received on the CPU it shares)
            job.alone = not self._running and not len(self._queue)
            for other in self._running:       # nor, from now on, beside these
                other.alone = False
            self._running.add(job)
            return job

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
        return 'busy: waited %.3g s in the queue; its deadline passed' % (
            job.started - job.queued_at)

    def done(self, job, seconds=None):
        """``job`` is finished; ``seconds`` of work (None: not a measure of the kind's
        work, e.g. a rejected task)."""
        with self._cond:
            self._running.discard(job)
            self.finished += 1
            if seconds is not None:
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
        """The :class:`Load` now; its backlog and utilization without the tasks of owner
        ``excluding`` (what a robot's next task waits for when the robot's own tasks are
        done by then: a robot that keeps one task out would otherwise see its own task as
        load on its server and none on the others, and move for nothing; leaving its own
        out of its server's utilization is what keeps it there: moving would add them to
        another's)."""
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
