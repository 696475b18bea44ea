"""Bookkeeping of a robot's tasks in flight: every task ends answered or failed, once."""

import collections
import threading

Outcome = collections.namedtuple(
    'Outcome', 'task_id send_time server_id answered_by ok error rtt')

NONE = -1


class TaskTracker(object):
    """Tasks sent and not yet resolved, with a deadline each.

    ``resolve`` is called for each result that arrives, ``expire`` periodically; each
    task yields exactly one :class:`Outcome` from one of them. A second result for a task
    already resolved is a duplicate (``resolve`` returns None and counts it).
    """

    def __init__(self, timeout, remember=10000):
        self.timeout = float(timeout)
        self._lock = threading.Lock()
        self._pending = collections.OrderedDict()
        self._done = collections.OrderedDict()
        self._remember = remember
        self.duplicates = 0
        self.unknown = 0

    def __len__(self):
        with self._lock:
            return len(self._pending)

    def sent(self, task_id, now, server_id, context=None):
        """Start tracking ``task_id``, sent at ``now`` to ``server_id``."""
        with self._lock:
            if task_id in self._pending or task_id in self._done:
                raise ValueError('task id %d already used' % task_id)
            self._pending[task_id] = (now, server_id, context)

    def context(self, task_id):
        """What was stored with a pending task (None if not pending)."""
        with self._lock:
            entry = self._pending.get(task_id)
        return entry[2] if entry else None

    def resolve(self, task_id, now, answered_by, ok, error=''):
        """The outcome of a result for ``task_id``, or None for a duplicate or unknown id."""
        with self._lock:
            entry = self._pending.pop(task_id, None)
            if entry is None:
                if task_id in self._done:
                    self.duplicates += 1
                else:
                    self.unknown += 1
                return None
            self._finish(task_id)
        send_time, server_id, _ = entry
        return Outcome(task_id, send_time, server_id, answered_by, bool(ok), error, now - send_time)

    def fail(self, task_id, now, server_id, error):
        """Record a task that could not even be sent (e.g. no server selected)."""
        with self._lock:
            self._finish(task_id)
        return Outcome(task_id, now, server_id, NONE, False, error, float('nan'))

    def expire(self, now):
        """Outcomes of the tasks whose deadline has passed (oldest first)."""
        expired = []
        with self._lock:
            for task_id, (send_time, server_id, _) in list(self._pending.items()):
                if now - send_time < self.timeout:
                    break
                del self._pending[task_id]
                self._finish(task_id)
                expired.append(Outcome(task_id, send_time, server_id, NONE, False,
                                       'no result within task_timeout %.3g s' % self.timeout,
                                       float('nan')))
        return expired

    def _finish(self, task_id):
        self._done[task_id] = True
        while len(self._done) > self._remember:
            self._done.popitem(last=False)
