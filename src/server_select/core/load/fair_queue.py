"""The tasks waiting for a server's workers, shared fairly between their senders (no rospy;
not thread-safe: the :class:`~server_select.core.load.work_queue.WorkQueue` holds its lock).

One sender that sends more than the others, or larger tasks, must not take the server from
them: a robot sending 100,000-value sorts at 68 a second once took every place in a
server's queue, and the other robots were answered busy. So each sender (a robot, by the id
its admission bound to its key) has a queue of its own:

- the workers take from them by *deficit round robin* (Shreedhar and Varghese, SIGCOMM
  '95) in seconds of work, so each sender waiting gets an equal share of the workers'
  time whatever its tasks' sizes, and a task waits behind at most about as much of each
  other sender's work as its own sender has queued before it;
- when the queue is full (places or bytes), a task of a sender holding less than the one
  holding most pushes out that one's newest task (*longest queue drop*): a sender can
  fill the queue while it is alone, and gives room back as soon as another sends.
"""

import collections

MIN_COST = 1e-6          # s: the least a task's turn costs (work not known yet counts 0)


class Job(object):
    """A task in a :class:`WorkQueue`: what the worker needs, its kind, deadline and
    owner (who sent it: a robot's id, or None); once taken, when it started and whether
    it ran alone (no other job started or ran beside it)."""
    __slots__ = ('kind', 'item', 'deadline', 'queued_at', 'started', 'owner', 'size', 'alone')

    def __init__(self, kind, item, deadline, queued_at, owner=None, size=0):
        self.kind, self.item, self.deadline, self.queued_at = kind, item, deadline, queued_at
        self.owner, self.size = owner, size
        self.started, self.alone = None, False


class FairQueue(object):
    """:class:`Job` s by their owner, in arrival order each."""

    def __init__(self):
        self._queues = collections.OrderedDict()   # owner -> deque of its jobs, none empty
        self._deficit = {}       # owner -> seconds of work it may take before the next
        self._count = 0
        self.bytes = 0

    def __len__(self):
        return self._count

    def jobs(self):
        """Every job queued (any order)."""
        for jobs in self._queues.values():
            yield from jobs

    def held(self, owner):
        """(jobs, bytes) ``owner`` has queued."""
        jobs = self._queues.get(owner, ())
        return len(jobs), sum(job.size for job in jobs)

    def push(self, job):
        self._queues.setdefault(job.owner, collections.deque()).append(job)
        self._count += 1
        self.bytes += job.size

    def pop(self, cost, allowed=None):
        """The next job by deficit round robin, ``cost(job)`` its seconds of work, of an
        owner that ``allowed(owner)`` (None: any) (None: no such job). The owner in turn
        takes jobs while its deficit covers them; one that cannot gets a quantum (the
        largest next job's cost, so that every owner takes one within a round) and waits
        for its next turn; an owner not allowed is passed over, its deficit kept."""
        owners = set(o for o in self._queues if allowed is None or allowed(o))
        if not owners:
            return None
        quantum = max(max(cost(self._queues[o][0]), MIN_COST) for o in owners)
        while True:
            owner, jobs = next(iter(self._queues.items()))
            if owner in owners:
                price = max(cost(jobs[0]), MIN_COST)
                if self._deficit.get(owner, 0.0) >= price:
                    self._deficit[owner] -= price
                    return self._remove(owner, jobs.popleft())
                self._deficit[owner] = self._deficit.get(owner, 0.0) + quantum
            self._queues.move_to_end(owner)

    def room_for(self, owner, size, max_count, max_bytes=None):
        """The jobs to push out so that one more of ``owner`` (``size`` bytes) fits in
        ``max_count`` jobs and ``max_bytes`` bytes (None: any): each the newest of the
        owner holding most, while that one would still hold more than ``owner`` (none are
        pushed out yet: the caller calls :meth:`push_out`); None when no such room can be
        made, [] when it fits as it is."""
        count, held = self._count, self.bytes
        own = self.held(owner)
        taken = collections.Counter()     # owner -> jobs planned out (its newest)
        plan = []
        while count >= max_count or (max_bytes is not None and count and
                                     held + size > max_bytes):
            by_bytes = count < max_count
            victim, amount = self._most(owner, taken, by_bytes)
            if victim is None or amount <= own[by_bytes] + (size if by_bytes else 1):
                return None
            taken[victim] += 1
            job = self._queues[victim][-taken[victim]]
            plan.append(job)
            count, held = count - 1, held - job.size
        return plan

    def push_out(self, jobs):
        for job in jobs:
            queue = self._queues[job.owner]
            queue.remove(job)
            self._remove(job.owner, job, queue)

    def wait_work(self, owner, cost, work):
        """Seconds of queued work one more job of ``owner`` (``cost`` s) waits behind: its
        owner's own, and of each other owner's at most its owner's own plus its cost (what
        the round robin serves them before it), ``work(job)`` each job's."""
        own = sum(work(job) for job in self._queues.get(owner, ()))
        return own + sum(min(sum(work(job) for job in jobs), own + cost)
                         for other, jobs in self._queues.items() if other != owner)

    def clear(self):
        """Every job, the queue left empty."""
        jobs = list(self.jobs())
        self._queues.clear()
        self._deficit.clear()
        self._count = self.bytes = 0
        return jobs

    def _most(self, owner, taken, by_bytes):
        """(the other owner holding most jobs, or bytes, once ``taken`` are out; that
        amount), or (None, 0)."""
        best, amount = None, 0
        for other, jobs in self._queues.items():
            if other == owner:
                continue
            left = list(jobs)[:len(jobs) - taken[other]]
            held = sum(job.size for job in left) if by_bytes else len(left)
            if left and held > amount:
                best, amount = other, held
        return best, amount

    def _remove(self, owner, job, jobs=None):
        jobs = self._queues[owner] if jobs is None else jobs
        if not jobs:
            del self._queues[owner]
            self._deficit.pop(owner, None)
        self._count -= 1
        self.bytes -= job.size
        return job
