"""A server's load: its bounded work queue, and what a robot makes of its reports (no rospy).

A task's round trip is the network, the wait for a worker and the work itself. A probe,
answered on its own thread, measures only the first; so every probe answer carries the
server's :class:`Load` (tasks queued and in service, workers, the *backlog*: seconds a
task sent now would wait for a worker, and the recent work per task of each kind), and a
robot ranks servers by round trip + backlog + work for the tasks it sends (C3's expected
completion, NSDI '15).

Server side, :class:`WorkQueue` holds the tasks waiting for the workers. A task carries
its *deadline* (when its robot stops waiting): one that cannot be finished by then is
refused at once (the robot hears "busy" and sends it elsewhere, or drops it for a newer
frame) instead of waiting in the queue for an answer nobody wants; one whose deadline
passes while it waits is shed when a worker takes it.
"""

import collections
import statistics
import threading
import time

Load = collections.namedtuple('Load', 'queued in_service workers backlog service')
Load.__doc__ = """One load report: ``service`` is ``{kind: seconds of work per task}``."""

IDLE = Load(0, 0, 1, 0.0, {})


class ServiceTimes(object):
    """The recent work per task of each kind: the median of the last ``keep`` (thread-safe)."""

    def __init__(self, keep=20):
        if keep < 1:
            raise ValueError('keep must be >= 1, got %r' % (keep,))
        self.keep = keep
        self._lock = threading.Lock()
        self._times = {}
        self._medians = {}

    def add(self, kind, seconds):
        with self._lock:
            times = self._times.get(kind)
            if times is None:
                times = self._times[kind] = collections.deque(maxlen=self.keep)
            times.append(float(seconds))
            self._medians[kind] = statistics.median(times)

    def get(self, kind):
        """Seconds of work per task of ``kind`` (0.0 while none was done: optimistic)."""
        return self._medians.get(kind, 0.0)

    def snapshot(self):
        """``{kind: seconds}`` of every kind done so far."""
        with self._lock:
            return dict(self._medians)


class Job(object):
    """A task in a :class:`WorkQueue`: what the worker needs, its kind, deadline and
    owner (who sent it: a robot's id, or None)."""
    __slots__ = ('kind', 'item', 'deadline', 'queued_at', 'started', 'owner')

    def __init__(self, kind, item, deadline, queued_at, owner=None):
        self.kind, self.item, self.deadline, self.queued_at = kind, item, deadline, queued_at
        self.owner = owner
        self.started = None


class WorkQueue(object):
    """Tasks waiting for ``workers`` workers, at most ``max_queue`` of them (thread-safe).

    :meth:`offer` queues a task or says at once why not (full, or it cannot be done by its
    deadline: busy); workers :meth:`take` the oldest (None once closed), ask
    :meth:`stale` whether its deadline has passed meanwhile, and call :meth:`done` with the
    seconds it took, which teach :class:`ServiceTimes`. Deadlines and times are those of
    ``clock``.
    """

    def __init__(self, workers, max_queue, times=None, clock=time.monotonic):
        if workers < 1 or max_queue < 1:
            raise ValueError('workers and max_queue must be >= 1, got %r, %r'
                             % (workers, max_queue))
        self.workers, self.max_queue = int(workers), int(max_queue)
        self.times = times or ServiceTimes()
        self._clock = clock
        self._cond = threading.Condition()
        self._queue = collections.deque()
        self._running = set()
        self._closed = False
        self.refused = self.shed = self.finished = 0

    def _backlog(self, now, excluding=None):
        """Seconds until a worker is free for one more task (call with the lock held),
        leaving out the tasks of owner ``excluding`` (None: counting every task)."""
        queued = [job for job in self._queue if excluding is None or job.owner != excluding]
        running = [job for job in self._running if excluding is None or job.owner != excluding]
        if len(running) + len(queued) < self.workers:
            return 0.0
        work = sum(self.times.get(job.kind) for job in queued)
        work += sum(max(0.0, self.times.get(job.kind) - (now - job.started)) for job in running)
        return work / self.workers

    def offer(self, kind, item, deadline=None, owner=None):
        """Queue ``item`` (a task of ``kind`` wanted by ``deadline``, None: whenever, sent
        by ``owner``). Returns None when queued, else why it is refused (it was not queued)."""
        with self._cond:
            now = self._clock()
            if self._closed:
                why = 'the server is shutting down'
            elif len(self._queue) >= self.max_queue:
                why = 'busy: %d tasks queued already' % len(self._queue)
            else:
                why = None
                if deadline is not None:
                    finish = self._backlog(now) + self.times.get(kind)
                    if now + finish > deadline:
                        why = 'busy: would finish in %.3g s, its deadline is in %.3g s' % (
                            finish, max(0.0, deadline - now))
            if why is not None:
                self.refused += 1
                return why
            self._queue.append(Job(kind, item, deadline, now, owner))
            self._cond.notify()
            return None

    def take(self):
        """The oldest queued job, once there is one (blocks); None once closed."""
        with self._cond:
            while not self._queue and not self._closed:
                self._cond.wait()
            if self._closed:
                return None
            job = self._queue.popleft()
            job.started = self._clock()
            self._running.add(job)
            return job

    def stale(self, job):
        """Why ``job`` (just taken) is not worth doing any more (its deadline would pass
        before its work is done), or None; a stale job counts as shed and is done."""
        if job.deadline is None:
            return None
        work = self.times.get(job.kind)
        if job.started + work <= job.deadline:
            return None
        with self._cond:
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
            self.times.add(job.kind, seconds)

    def load(self, excluding=None):
        """The :class:`Load` now; its backlog without the tasks of owner ``excluding``
        (what a robot's next task waits for when the robot's own tasks are done by then:
        a robot that keeps one task out would otherwise see its own task as load on its
        server and none on the others, and move for nothing)."""
        with self._cond:
            now = self._clock()
            return Load(len(self._queue), len(self._running), self.workers,
                        self._backlog(now, excluding), self.times.snapshot())

    def close(self):
        """Wake every worker with None; what is still queued is dropped (returned)."""
        with self._cond:
            self._closed = True
            dropped, self._queue = list(self._queue), collections.deque()
            self._cond.notify_all()
            return dropped


class LoadBoard(object):
    """A robot's view of its servers' load: the newest report of each, and its own tasks
    sent to each since (thread-safe).

    ``mix`` is ``{kind: weight}`` of the tasks the robot sends (its streams' rates): the
    *wait* of a server is its backlog plus the mix's work there, what :meth:`wait` adds to
    a probe's round trip so that servers rank by expected completion. A report older than
    ``max_age`` s counts as none (the probes stopped: health decides then). A server that
    has not yet done a task of a kind is taken to need the median of what the others
    report for it: not nothing, or every robot would rush to a server that just came up.
    """

    def __init__(self, mix, max_age=2.0, clock=time.monotonic):
        total = float(sum(mix.values()))
        if not mix or not total > 0:
            raise ValueError('mix must give a positive weight to some kind, got %r' % (mix,))
        self.mix = dict((k, w / total) for k, w in mix.items())
        self.max_age = max_age
        self._clock = clock
        self._lock = threading.Lock()
        self._reports = {}       # server -> [Load, time, tasks sent since]

    def update(self, server, load):
        with self._lock:
            self._reports[server] = [load, self._clock(), collections.Counter()]

    def sent(self, server, kind):
        """One of the robot's tasks went to ``server`` (it is in no report yet)."""
        with self._lock:
            report = self._reports.get(server)
            if report is not None:
                report[2][kind] += 1

    def forget(self, server):
        with self._lock:
            self._reports.pop(server, None)

    def _fresh(self, server):
        report = self._reports.get(server)
        if report is None or self._clock() - report[1] > self.max_age:
            return None
        return report

    def _work(self, load, kind):
        """Seconds of work per ``kind`` task by ``load``, else the others' median."""
        seconds = load.service.get(kind)
        if seconds is not None:
            return seconds
        known = [r[0].service[kind] for r in self._reports.values()
                 if kind in r[0].service and self._clock() - r[1] <= self.max_age]
        return statistics.median(known) if known else 0.0

    def wait(self, server):
        """Backlog + the mix's work at ``server`` (s) by its newest report; None: none."""
        with self._lock:
            report = self._fresh(server)
            if report is None:
                return None
            load = report[0]
            return load.backlog + sum(w * self._work(load, k) for k, w in self.mix.items())

    def expected(self, server, kind):
        """Seconds from a task of ``kind`` reaching ``server`` to its answer leaving it, by
        the newest report plus the robot's own tasks sent since (None: no fresh report)."""
        with self._lock:
            report = self._fresh(server)
            if report is None:
                return None
            load, _, since = report
            extra = sum(self._work(load, k) * n for k, n in since.items())
            return load.backlog + extra / max(1, load.workers) + self._work(load, kind)
