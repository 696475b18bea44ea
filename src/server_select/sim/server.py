"""A simulated compute server: the package's :class:`WorkQueue` on a host of finite CPU
(no rospy).

Tasks are offered to the queue as the node offers them (a deadline from the robot's
budget, the robot as owner) and answered busy at once when refused; ``workers`` take them
in order. A task's duration is its work (CPU seconds on one core, drawn per task, so that
every variant of a seed meets the same task sizes) over the host's CPU share per busy
worker, plus the scenario's extra ``work`` delay; on a host of less than a core, whose one
worker the cgroup's quota stops when it is spent, the work runs at full speed within the
quota of each ``cpu_period`` (:class:`~server_select.sim.quota.CpuQuota`). A worker's first
task of a kind is not timed, as the node's is not. While no robot sends here, a probe's
answer offers a check of an idle kind (``check_every``), as the node's does: a task of the
work of that kind's last, timed and answered to nobody. While the host hangs (SIGSTOP) nothing
runs and nothing is answered: work and answers resume when it goes on. A probe is
answered after its CPU (at full speed on a host of less than a core), which with a busy
worker there waits for the next quota period (``cpu_period``), as a cgroup throttles it.
"""

import collections
import math

from server_select.core.load.work_queue import CHECK, WorkQueue
from server_select.sim.quota import CpuQuota


# a check's task: the CPU s its kind's last task takes alone (a rerun of it: the host's
# share of each run is drawn anew)
Check = collections.namedtuple('Check', 'alone')


class SimServer(object):
    """Server ``host`` (a scenario Host) on ``loop``; ``reply(task, result)`` sends a
    result back."""

    def __init__(self, loop, host, model, streams, check_every=0.0, max_queue=100, cores=2):
        self.loop, self.host, self.model = loop, host, model
        self.check_every = check_every
        self.last_alone = {}      # kind -> its last task's CPU s alone (what a check reruns)
        self.id = host.id
        self.cpu = host.cpu
        self.workers = int(math.ceil(self.cpu)) if self.cpu else cores
        self.queue = WorkQueue(self.workers, max_queue, clock=loop.now,
                               on_pushed_out=self._pushed_out)
        self.rng = streams.rng('server', self.id)
        self.check_rng = streams.rng('check', self.id)    # a check's share of the host
        period = host.cpu_period * 1e-3
        self.quota = CpuQuota(self.cpu, period, streams.rng('quota', self.id).uniform(
            0.0, period)) if self.cpu and self.cpu < 1.0 else None
        self.idle = self.workers
        self.waiting = 0          # accepted, not yet taken
        self.timed = set()        # kinds a worker has done once (the first is not timed)
        self.completions = []     # when each task's work was done
        self.stolen = 0.0         # CPU s probes took from the workers' quota
        self.unwarmed = set(k for k, seconds in model.warm.items() if seconds > 0)
        self.warm_until = 0.0     # workers wait for what a kind needs to be loaded
        self._warm_wake = False   # a call of _start_workers is due at warm_until

    # -- state of the host ----------------------------------------------------------------
    def running(self, t):
        """Whether the server's process exists at ``t`` (its host's start and stop)."""
        return self.host.start <= t and (self.host.stop is None or t < self.host.stop)

    def resumed(self, t):
        """``t``, or when a hang that covers ``t`` ends."""
        for start, end in self.host.hang:
            if start <= t < end:
                return end
        return t

    def _after_hangs(self, start, seconds):
        """When ``seconds`` of running time from ``start`` end, hangs skipped."""
        t = self.resumed(start)
        for a, b in self.host.hang:
            if b <= t:
                continue
            if a < t + seconds:
                seconds -= max(0.0, a - t)
                t = b
            else:
                break
        return t + seconds

    def _extra_delay(self, t):
        extra = [delay for at, delay in self.host.work if at <= t]
        return extra[-1] if extra else 0.0

    def _speed(self):
        return min(1.0, self.cpu / self.workers) if self.cpu else 1.0

    def _cpu(self, start, seconds):
        """How long ``seconds`` of a worker's CPU take from ``start``."""
        if self.quota is None:
            return seconds / self._speed()
        return self.quota.run(start, seconds) - start

    # -- probes ---------------------------------------------------------------------------
    def probe_done(self, t):
        """When a probe that arrived at ``t`` is answered (None: not running: refused)."""
        if not self.running(t):
            return None
        t = self.resumed(t)
        seconds = self.model.probe_cpu * self.model.cpu_factor
        if self.quota is None:
            seconds /= self.cpu or 1.0
        elif self.idle < self.workers:
            # the worker used the quota: the probe waits for the next period's
            seconds += self.rng.uniform(0.0, self.quota.period * (1.0 - self.cpu))
        return self._after_hangs(t, seconds)

    def probe(self, robot, rates):
        """The Load a probe of ``robot`` announcing ``rates`` gets (at its answer). On a
        capped host its CPU comes out of the quota the workers use: the task in service
        finishes that much later."""
        self.queue.announce(robot, rates)
        now = self.loop.now()
        for kind in self.unwarmed.intersection(k for k, _ in rates):
            self.unwarmed.discard(kind)
            self.warm_until = max(now, self.warm_until) + self.model.warm[kind] * \
                self.model.cpu_factor / min(1.0, self.cpu or 1.0)
        if self.cpu and self.idle < self.workers:
            self.stolen += self.model.probe_cpu * self.model.cpu_factor
        if self.queue.offer_check(self.check_every, lambda kind: (
                Check(self.last_alone[kind]), None) if kind in self.last_alone else None):
            self.waiting += 1
            self._start_workers()
        return self.queue.load(excluding=robot)

    # -- tasks ----------------------------------------------------------------------------
    def submit(self, task, budget, reply):
        """A task arrives: queued, or answered busy at once; ``reply(task, ok, error,
        busy)`` at its answer."""
        now = self.loop.now()
        if not self.running(now):
            return                    # no subscriber: the message reaches nobody
        resume = self.resumed(now)
        if resume > now:
            self.loop.at(resume, self.submit, task, budget, reply)
            return
        deadline = now + budget if budget > 0 else None
        why = self.queue.offer(task.kind, (task, reply), deadline, owner=task.robot)
        if why is not None:
            reply(task, False, why, True)
            return
        self.waiting += 1
        self._start_workers()

    def _pushed_out(self, job, why):
        """A task a robot holding less of the queue pushed out: answered busy."""
        self.waiting -= 1
        task, reply = job.item
        reply(task, False, why, True)

    def _start_workers(self):
        now = self.loop.now()
        if now < self.warm_until:           # its first task waits for the kind's load
            if not self._warm_wake:
                self._warm_wake = True
                self.loop.at(self.warm_until, self._warmed)
            return
        while self.idle and self.waiting:
            job = self.queue.take(wait=False)
            if job is None:     # a robot holding all workers but one, while others send
                return
            self.waiting -= 1
            task, reply = job.item
            why = self.queue.stale(job)
            if why is not None:
                reply(task, False, why, True)
                continue
            self.idle -= 1
            now = self.loop.now()
            if job.owner == CHECK:
                cpu = task.alone + self.model.shared_delay(self.check_rng)
            else:
                cpu, self.last_alone[job.kind] = task.work, task.alone
            if job.kind in self.unwarmed:      # nobody announced it: its first task loads
                self.unwarmed.discard(job.kind)
                cpu += self.model.warm[job.kind] * self.model.cpu_factor
            seconds = self._cpu(now, cpu) + self._extra_delay(now)
            self.loop.at(self._after_hangs(now, seconds), self._finished, job, seconds)

    def _warmed(self):
        self._warm_wake = False
        self._start_workers()

    def _finished(self, job, seconds):
        if self.stolen > 0:               # probes used some of the quota meanwhile
            now = self.loop.now()
            delay, self.stolen = self._cpu(now, self.stolen) if self.quota else \
                self.stolen / self.cpu, 0.0
            self.loop.at(self._after_hangs(now, delay), self._finished, job,
                         seconds + delay)
            return
        task, reply = job.item
        first = job.kind not in self.timed
        self.timed.add(job.kind)
        self.queue.done(job, None if first else seconds)
        self.idle += 1
        if not self.running(self.loop.now()):
            return                    # the process was stopped: no answer, no more work
        if job.owner != CHECK:        # (a check is answered to nobody)
            self.completions.append(self.loop.now())
            reply(task, True, '', False)
        self._start_workers()
