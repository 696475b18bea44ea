"""A server's workers: the tasks of every kind through one bounded queue
(:class:`~server_select.core.load.work_queue.WorkQueue`), answered by ``workers`` threads."""

import threading
import time

import rospy

from server_select.core.load.pauses import Pauses
from server_select.core.load.work_queue import CHECK, WorkQueue
from server_select.core.trust.senders import SenderThrottle, Throttle


class ServerWork(object):
    """Takes the tasks addressed to this server from its endpoints
    (:class:`~server_select.ros.endpoints.ServerEndpoint`), and answers each exactly once: a
    result from a worker, or at once a *busy* result when the task cannot be finished by
    the deadline its robot gave (``budget``), or the queue is full; a task whose deadline
    passed while it waited, or that a task of a robot holding less of the queue pushed
    out, is answered busy too, without doing the work. While nobody sends here, a copy of
    the last task of a kind none of whose tasks was timed in the last ``check_every`` s is
    worked on again (:meth:`check`), its result going nowhere."""

    def __init__(self, server_id, workers, max_queue, max_queue_bytes=None,
                 clock=time.monotonic):
        self.server_id, self._clock = server_id, clock
        self.queue = WorkQueue(workers, max_queue, max_bytes=max_queue_bytes, clock=clock,
                               on_pushed_out=lambda job, why: self._busy(*job.item, why))
        self._lock = threading.Lock()
        self.busy = self.checks = 0
        self._last = {}          # kind -> (endpoint, task) of its last task done
        self._unrehearsed = set()    # kinds whose type does not rehearse a task
        self.pauses = Pauses(clock=clock)
        self._paused_lines = Throttle(5.0, clock=clock)
        self._busy_lines = SenderThrottle(5.0, clock=clock)    # a line per robot

    def start(self):
        for index in range(self.queue.workers):
            threading.Thread(target=self._run, name='worker%d' % index, daemon=True).start()
        threading.Thread(target=self.pauses.run, args=(rospy.is_shutdown,), name='pauses',
                         daemon=True).start()

    def submit(self, endpoint, task, direct):
        """A task addressed here (from a subscriber's thread: never blocks)."""
        budget = getattr(task, 'budget', 0.0)
        deadline = self._clock() + budget if budget > 0 else None
        why = self.queue.offer(endpoint.kind_name, (endpoint, task, direct), deadline,
                               owner=task.robot_id, size=endpoint.held_bytes(task))
        if why is not None:
            self._busy(endpoint, task, direct, why)

    def _run(self):
        # a worker's first task of a kind also loads what the kind needs (OpenCV imported,
        # a detector built: seconds on a slow host): its time is not the kind's work, and
        # reported as such it made every server look seconds slow in turn as robots came
        loaded = set()
        while True:
            job = self.queue.take()
            if job is None:
                return
            endpoint, task, direct = job.item
            why = self.queue.stale(job)
            if why is not None:
                self._busy(endpoint, task, direct, why)
                continue
            start, check = self._clock(), job.owner == CHECK
            try:
                result = endpoint.rehearse(task) if check else endpoint.handle(task)
            except Exception as error:    # a defect in one handler must not stop a worker
                self.queue.done(job)
                rospy.logerr('server %d: %s task %d of robot %d%s: %s: %s', self.server_id,
                             endpoint.kind_name, task.task_id, task.robot_id,
                             ' (a check; the kind is not checked again)' if check else '',
                             type(error).__name__, error)
                if check:
                    self._checked(job.kind, False)
                else:
                    endpoint.reply(task, direct, endpoint.error_result(
                        task, 'server error: %s' % error))
                continue
            first = job.kind not in loaded
            loaded.add(job.kind)
            ok = result is not False if check else result.ok
            self.queue.done(job, self._work(job.kind, start) if ok and not first else None)
            if check:
                self._checked(job.kind, result)
            else:
                if ok:
                    self._last[job.kind] = (endpoint, task)
                endpoint.reply(task, direct, result)

    def check(self, every):
        """While nobody sends here, a check of a kind due one (a probe came: from a probe's
        thread; never blocks; :meth:`WorkQueue.offer_check`)."""
        def item_of(kind):
            last = None if kind in self._unrehearsed else self._last.get(kind)
            return last and last + (None,)
        self.queue.offer_check(every, item_of)

    def _checked(self, kind, rehearsed):
        with self._lock:
            self.checks += rehearsed is not False
        if rehearsed is False:
            self._unrehearsed.add(kind)

    def _work(self, kind, start):
        """The seconds of work a task begun at ``start`` took, or None when the process
        stood still meanwhile (its time says nothing of the kind's work)."""
        end = self._clock()
        if not self.pauses.across(start, end):
            return end - start
        due, held = self._paused_lines.due()
        if due:
            rospy.loginfo('server %d: a %s task was timed across a pause of this process; '
                          'its %.1f s are not counted as work (%d more such since the last '
                          'line)' % (self.server_id, kind, end - start, held))
        return None

    def _busy(self, endpoint, task, direct, why):
        with self._lock:
            self.busy += 1
            count = self.busy
        due, held = self._busy_lines.due(task.robot_id)
        if due:
            rospy.logwarn('server %d: answered %s task %d of robot %d busy: %s (%d busy answers '
                          'so far%s)' % (self.server_id, endpoint.kind_name, task.task_id,
                                         task.robot_id, why, count, '; %d more to robot %d '
                                         'before' % (held, task.robot_id) if held else ''))
        endpoint.reply(task, direct, endpoint.error_result(task, why, busy=True))

    def announce(self, robot, rates):
        """``robot``'s probe says it sends ``(kind, tasks per second)`` pairs here now."""
        self.queue.announce(robot, rates)

    def load(self, robot=None):
        """The load as ``robot`` sees it (its own tasks left out of the backlog)."""
        return self.queue.load(excluding=robot)

    def summary(self):
        queue = self.queue
        return '%d workers, %d tasks worked on, %d answered busy (%d of them shed from the ' \
            'queue), %d checks of an idle kind' % (queue.workers, queue.finished, self.busy,
                                                   queue.shed, self.checks)

    def shutdown(self):
        """Stop the workers; tasks still queued get no answer (their robots re-send)."""
        return self.queue.close()
