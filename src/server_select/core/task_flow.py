"""The robot's task path without ROS: make, send, check and track tasks, report each once.

A :class:`TaskFlow` is handed callables for everything outside it (where to send, how to
make and publish a request, how to check a result, where reports go, the clock), so it is
tested without a master. It goes forward only::

    send_next(stamp) -> target() -> make(task_id, server, stamp) -> publish(request)
    resolve(result)  -> check(result, context) -> report(Outcome)     # an answer
    expire()         -> report(Outcome)                               # the deadline

Every task sent yields exactly one :class:`Outcome`: answered (checked), failed (error
result, wrong result, no answer within ``timeout``) or not sent at all (no server).
"""

import collections
import itertools
import threading
import time

from server_select.msg import TaskReport

NO_SERVER = TaskReport.NO_SERVER
LOCAL = TaskReport.LOCAL

Pending = collections.namedtuple('Pending', 'task_id server_id stamp sent_at context')
Pending.__doc__ = """A task in flight: where it went, its send stamp (for the report header),
its send time on the flow's clock, and what ``check`` needs to judge the answer."""

Outcome = collections.namedtuple(
    'Outcome', 'task_id kind stamp server_id answered_by ok error rtt')
Outcome.__doc__ = """How one task ended, as published on ``task_report`` (``rtt`` is None
when no answer arrived)."""

# What became of a result that resolves nothing.
DUPLICATE, LATE, UNKNOWN = 'duplicate', 'late', 'unknown'


class TaskFlow(object):
    """One stream of tasks of one robot, from creation to its one report.

    :param kind: task type name (``sort``, ``image``) carried in every report.
    :param timeout: seconds a task may wait for its answer.
    :param target: ``() -> server id``, ``NO_SERVER`` or ``LOCAL`` (process it here).
    :param make: ``(task_id, server_id, stamp) -> (request, context)``.
    :param publish: ``(request) -> None``.
    :param check: ``(result, context) -> error string or None`` for a result reported ok.
    :param report: ``(Outcome) -> None``, called once per task.
    :param run_local: ``(task_id, stamp) -> error or None``: the work done in the robot
        when ``target()`` says ``LOCAL``.
    :param ids: iterator of task ids (shared by the robot's streams: ids are per robot).
    """

    def __init__(self, kind, timeout, target, make, publish, check, report, run_local=None,
                 ids=None, clock=time.monotonic, remember=10000, keep_rtts=10000):
        if not timeout > 0:
            raise ValueError('timeout must be positive, got %r' % (timeout,))
        self.kind = kind
        self.timeout = float(timeout)
        self._target, self._make, self._publish = target, make, publish
        self._check, self._report, self._run_local = check, report, run_local
        self._ids = ids if ids is not None else itertools.count(1)
        self._clock = clock
        self._lock = threading.Lock()
        self._pending = collections.OrderedDict()     # task id -> Pending, oldest first
        self._ended = collections.OrderedDict()       # task id -> True (answered) / False
        self._remember = remember
        self.sent = 0
        self.ok = 0
        self.failed = 0
        self.ignored = collections.Counter()          # DUPLICATE / LATE / UNKNOWN results
        self.rtts = collections.deque(maxlen=keep_rtts)   # recent answered round trips

    def __len__(self):
        with self._lock:
            return len(self._pending)

    def send_next(self, stamp):
        """Make one task now and send it where ``target()`` says; returns its id."""
        task_id = next(self._ids)
        server = self._target()
        with self._lock:
            self.sent += 1
        if server == NO_SERVER:
            self._end(Outcome(task_id, self.kind, stamp, NO_SERVER, NO_SERVER, False,
                              'no server selected', None))
        elif server == LOCAL:
            start = self._clock()
            error = self._run_local(task_id, stamp)
            self._end(Outcome(task_id, self.kind, stamp, LOCAL, LOCAL, not error, error or '',
                              self._clock() - start))
        else:
            request, context = self._make(task_id, server, stamp)
            with self._lock:
                self._pending[task_id] = Pending(task_id, server, stamp, self._clock(), context)
            self._publish(request)
        return task_id

    def resolve(self, task_id, answered_by, ok, error='', result=None):
        """An answer for ``task_id``: its Outcome, or DUPLICATE / LATE / UNKNOWN."""
        now = self._clock()
        with self._lock:
            pending = self._pending.pop(task_id, None)
            if pending is None:
                why = UNKNOWN if task_id not in self._ended else (
                    DUPLICATE if self._ended[task_id] else LATE)
                self.ignored[why] += 1
                return why
        if ok:
            error = self._check(result, pending.context) or ''
            ok = not error
        return self._end(Outcome(task_id, self.kind, pending.stamp, pending.server_id,
                                 answered_by, bool(ok), error, now - pending.sent_at))

    def expire(self):
        """Report the tasks whose deadline has passed (oldest first); returns them."""
        now = self._clock()
        expired = []
        with self._lock:
            while self._pending:
                pending = next(iter(self._pending.values()))
                if now - pending.sent_at < self.timeout:
                    break
                del self._pending[pending.task_id]
                expired.append(pending)
        return [self._end(Outcome(p.task_id, self.kind, p.stamp, p.server_id, NO_SERVER,
                                  False, 'no result within task_timeout %.3g s' % self.timeout,
                                  None))
                for p in expired]

    def _end(self, outcome):
        with self._lock:
            self._ended[outcome.task_id] = outcome.answered_by != NO_SERVER
            while len(self._ended) > self._remember:
                self._ended.popitem(last=False)
            if outcome.ok:
                self.ok += 1
                self.rtts.append(outcome.rtt)
            else:
                self.failed += 1
        self._report(outcome)
        return outcome
