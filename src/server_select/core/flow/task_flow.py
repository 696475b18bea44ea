"""The robot's task path without ROS: make, send, re-send, check, report each task once.

A :class:`TaskFlow` is handed callables for everything outside it (where to send, how to
make and publish a request, how to check a result, where evidence and reports go, the
clock), so it is tested without a master. It goes forward only::

    send_next(stamp) -> candidates() -> make(task_id, stamp) -> publish(request, server, budget)
    tick()           -> an attempt's deadline passed: on_failure(server), publish to the next
                        candidate; the task's timeout passed: report(Outcome)
    resolve(result)  -> check(result, context) -> on_success(server) -> report(Outcome)

Tasks are idempotent and carry their id: a task without an answer by its attempt deadline
(a multiple of that server's recent round trips) is sent again to the next candidate it
has not tried, and the first answer from any server it was sent to wins; later ones are
counted as duplicates. With ``hedge`` (a quantile, :data:`HEDGE_QUANTILE`), a task still
unanswered a median round trip after that quantile of its server's recent round trips is
also sent to the next candidate without blaming the first ("The Tail at Scale"'s hedged
request). Every task yields exactly one :class:`Outcome`.

Under overload (docs/design.md, "Capacity and overload") a *busy* answer blames nobody; extra
sends are paid from a ``budget``; at most ``max_in_flight`` tasks are out at once, and with
``newest_wins`` a late task gives way to a newer one that is held back.
"""

import collections
import itertools
import threading
import time

from server_select.core.flow.attempts import AttemptClock, Pending
from server_select.core.flow.timing import Timing
from server_select.core.flow.outcome import (DUPLICATE, ENDED, FOREIGN, LATE,  # noqa: F401
                                             LOCAL, NO_SERVER, OUTRUN, RETRIED, UNKNOWN,
                                             EndedTasks,
                                             Outcome, Resolution)

# a hedged copy goes after this quantile of a server's round trips, plus their median
# ("The Tail at Scale": the p95)
HEDGE_QUANTILE = 0.95


class TaskFlow(Timing):
    """One stream of tasks of one robot, from creation to its one report.

    :param candidates: ``() -> [server ids]`` in order of preference, ``[LOCAL]`` to work
        in the robot, ``[]`` when there is none.
    :param make: ``(task_id, stamp) -> (request, context)``; a ValueError it raises fails
        the task (reported, not sent).
    :param publish: ``(request, server_id, budget) -> None``; ``budget``: seconds left of
        the task's timeout (what the server is told it has).
    :param check: ``(result, context) -> error string or None`` for a result reported ok.
    :param report: ``(Outcome) -> None``, called once per task.
    :param run_local: ``(task_id, stamp) -> error or None``: the work done in the robot.
    :param on_failure, on_success: ``(server, why)`` / ``(server)``: evidence about servers;
        ``on_busy(server)``: it answered busy (no failure).
    :param on_answer: ``(server, rtt)``: an accepted answer of a task sent once, and its
        round trip (a latency sample of what tasks get; the answer of a hedged or re-sent
        task is not one: only the faster of two servers answers it).
    :param deadlines: an :class:`~server_select.core.flow.attempts.AttemptClock`.
    :param ids: iterator of task ids (shared by the robot's streams: ids are per robot).
    :param hedge: None, or the quantile of a server's round trips after which (plus
        their median) an unanswered task is also sent to the next candidate.
    :param budget: a :class:`~server_select.core.flow.budget.RetryBudget` (None: no limit).
    :param max_in_flight: at most this many tasks out at once (0: no limit); a send that
        finds them all out is held back (no task is made) until one ends (:meth:`due`).
    :param newest_wins: a task whose attempt deadline passes, or that is refused as busy,
        while a newer one is held back ends there instead of going elsewhere.
    :param attempts: told of every attempt: ``started(server, kind, first, order)`` when
        it is sent (``order``: the candidates it was chosen from),
        ``ended(server, rtt)`` once, when its answer came (``rtt``: since it was sent), it
        failed (an error, or its deadline passed: ``rtt`` is how long that took), or it
        stopped counting (``rtt`` None: a busy answer, another attempt won, the task
        ended); a :class:`~server_select.core.rule.balancer.Balancer`.
    :param copies: each task goes to this many candidates at once (replication; the
        copies are not paid from ``budget``).
    """

    def __init__(self, kind, timeout, candidates, make, publish, check, report, run_local=None,
                 on_failure=None, on_success=None, deadlines=None, ids=None,
                 clock=time.monotonic, remember=2000, keep_rtts=2000, hedge=None,
                 on_answer=None, budget=None, max_in_flight=0, newest_wins=False,
                 on_busy=None, attempts=None, copies=1):
        if not timeout > 0:
            raise ValueError('timeout must be positive, got %r' % (timeout,))
        self.kind, self.timeout = kind, float(timeout)
        self._candidates, self._make, self._publish = candidates, make, publish
        self._check, self._report, self._run_local = check, report, run_local
        self._on_failure = on_failure or (lambda server, why: None)
        self._on_success = on_success or (lambda server: None)
        self._on_answer = on_answer or (lambda server, rtt: None)
        self._on_busy = on_busy or (lambda server: None)
        self._attempts = attempts
        self.copies = max(1, int(copies))
        self.deadlines = deadlines or AttemptClock(self.timeout)
        self._ids = ids if ids is not None else itertools.count(1)
        self._clock = clock
        self._lock = threading.RLock()
        self._pending = collections.OrderedDict()     # task id -> _Pending, oldest first
        self._ended = EndedTasks(remember)
        self.hedge = hedge
        self.budget, self.max_in_flight, self.newest_wins = budget, max_in_flight, newest_wins
        self._held = False            # a send was held back by max_in_flight
        self.sent = self.ok = self.failed = self.resent = self.switches = self.hedged = 0
        self.busy = self.skipped = self.superseded = self.unfunded = self.replicated = 0
        self._last_first = None
        self.ignored = collections.Counter()   # DUPLICATE / OUTRUN / LATE / UNKNOWN / FOREIGN
        self.rtts = collections.deque(maxlen=keep_rtts)   # recent answered round trips
        # server -> attempts sent there since it last answered anything (stranded tasks)
        self._silent = collections.Counter()

    def candidates(self):
        """Where a task may go now, best first."""
        return self._candidates()

    def __len__(self):
        with self._lock:
            return len(self._pending)

    def due(self):
        """Whether a send was held back and may go now (a task has ended since)."""
        with self._lock:
            return self._held and len(self._pending) < self.max_in_flight

    def send_next(self, stamp):
        """Make one task now and send it to the first candidate; returns its id, or None
        when ``max_in_flight`` tasks are out (the send is held back until one ends)."""
        with self._lock:
            if self.max_in_flight and len(self._pending) >= self.max_in_flight:
                if not self._held:
                    self._held = True
                else:
                    self.skipped += 1     # a newer send replaces the one held back
                return None
            self._held = False
            self.sent += 1
        task_id = next(self._ids)
        candidates = self._candidates()
        if not candidates:
            return self._end(Outcome(task_id, self.kind, stamp, NO_SERVER, NO_SERVER, False,
                                     'no server selected', None, 0)).task_id
        if candidates[0] == LOCAL:
            start = self._clock()
            error = self._run_local(task_id, stamp)
            return self._end(Outcome(task_id, self.kind, stamp, LOCAL, LOCAL, not error,
                                     error or '', self._clock() - start, 1)).task_id
        try:
            request, context = self._make(task_id, stamp)
        except ValueError as error:   # e.g. a camera frame that does not decode
            return self._end(Outcome(task_id, self.kind, stamp, NO_SERVER, NO_SERVER, False,
                                     'cannot make the task: %s' % error, None, 0)).task_id
        with self._lock:
            pending = self._pending[task_id] = Pending(task_id, stamp, request, context,
                                                       self._clock())
            if candidates[0] != self._last_first and self._last_first is not None:
                self.switches += 1
            self._last_first = candidates[0]
            self._attempt(pending, candidates[0], candidates)
            for server in [s for s in candidates[1:] if s != LOCAL][:self.copies - 1]:
                self.replicated += 1
                self._attempt(pending, server, candidates)
        if self.budget is not None:
            self.budget.sent()
        return task_id

    def _attempt(self, pending, server, order):
        now = self._clock()
        pending.attempt(server, now, self._attempts, self.kind, order)
        self._silent[server] += 1
        pending.deadline = min(pending.started + self.timeout,
                               now + self.deadlines.seconds(server))
        self._publish(pending.request, server, self.deadlines.budget(
            server, pending.started + self.timeout - now, now - pending.started))

    def _drop(self, pending):
        """``pending`` is over: out of the table, its open attempts ended."""
        self._pending.pop(pending.task_id, None)
        pending.end(None, observer=self._attempts)

    def resolve(self, task_id, answered_by, ok, error='', result=None, busy=False):
        """An answer for ``task_id`` from ``answered_by``: a :class:`Resolution`, ENDED with
        the task's Outcome, RETRIED (an error or ``busy`` answer, the task went to the next
        candidate), or DUPLICATE / OUTRUN / LATE / UNKNOWN / FOREIGN (ignored: the task
        ended, or it was not sent there). A ``busy`` answer blames nobody."""
        now = self._clock()
        with self._lock:
            self._silent.pop(answered_by, None)     # it is up, late or not
            pending = self._pending.get(task_id)
            if pending is None:
                why = self._ended.why(task_id, answered_by)
                self.ignored[why] += 1
                return Resolution(why, None)
            sent_at = pending.sent_at(answered_by)
            if sent_at is None:
                self.ignored[FOREIGN] += 1
                return Resolution(FOREIGN, None)
            if ok:
                error = self._check(result, pending.context) or ''
                ok = not error
            if ok:
                answer_rtt = now - sent_at
                pending.end(answered_by, answer_rtt, self._attempts)
                self._drop(pending)
                self.deadlines.add(answered_by, answer_rtt)
            else:
                pending.end(answered_by, None if busy else now - sent_at, self._attempts)
                self.busy += busy
                if busy:
                    error = 'server %d busy (%s)' % (answered_by, error)
                    self._on_busy(answered_by)
                else:
                    self._on_failure(answered_by, error)
                if busy and self._gives_way():
                    error += '; a newer task waits'
                elif self._next(pending):
                    return Resolution(RETRIED, None)
                self._drop(pending)
        if ok:
            self._on_success(answered_by)
            if len(pending.attempts) == 1:    # the winner of a race is no fair sample
                self._on_answer(answered_by, answer_rtt)
        return Resolution(ENDED, self._end(pending.outcome(self.kind, answered_by, ok, error,
                                                           now - pending.started),
                                           pending.servers()))

    def abandon(self, why):
        """Report every task still waiting for an answer failed, with ``why`` (the robot is
        stopping: each task is reported once, none is left unsaid). Returns their Outcomes."""
        with self._lock:
            pending = list(self._pending.values())
            for each in pending:
                self._drop(each)
        return [self._end(p.unanswered(self.kind, why)) for p in pending]

    def _end(self, outcome, sent_to=()):
        with self._lock:
            self._ended.add(outcome.task_id, outcome.answered_by, sent_to)
            if outcome.ok:
                self.ok += 1
                self.rtts.append(outcome.rtt)
            else:
                self.failed += 1
        self._report(outcome)
        return outcome
