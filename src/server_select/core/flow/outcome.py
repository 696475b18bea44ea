"""A task's life at the robot: in flight (:class:`Pending`) and how it ended
(:class:`Outcome`), with the constants a ``task_report`` uses (no rospy, no messages: the
unit tests pin the constants equal to ``TaskReport``'s)."""

import collections

from server_select.core.config.names import LOCAL, NO_SERVER  # noqa: F401 (re-exported)
# The error of a task the robot still had out when it stopped (Ctrl-C, the end of a run, a
# newer copy taking its name): reported so that no task goes unsaid, but the run's end cut
# it off, so the evaluation leaves it out of a run's figures (:func:`cut_off`).
STOPPED = 'the robot stopped before an answer came'


def cut_off(error):
    """Whether a task report's ``error`` says the robot's stop cut the task off."""
    return error.startswith(STOPPED)


Outcome = collections.namedtuple(
    'Outcome', 'task_id kind stamp server_id answered_by ok error rtt attempts')
Outcome.__doc__ = """How one task ended, as published on ``task_report``: ``server_id`` is
the first server it was sent to, ``rtt`` None when no answer arrived."""

# What an answer did: ENDED its task (the Resolution has its Outcome); RETRIED: an error or
# busy answer, the task went to the next candidate; the others resolve nothing (ignored).
ENDED, RETRIED = 'ended', 'retried'
DUPLICATE, LATE, UNKNOWN, FOREIGN = 'duplicate', 'late', 'unknown', 'foreign'
# a copy of an answered task (a hedge, a re-send) answered by another server it was sent to:
# expected, and no fault of anyone's
OUTRUN = 'outrun'

Resolution = collections.namedtuple('Resolution', 'status outcome')
Resolution.__doc__ = """What an answer did: ``status`` (ENDED, RETRIED, DUPLICATE, OUTRUN,
LATE, UNKNOWN or FOREIGN) and, when ENDED, the task's ``outcome`` (else None)."""


class EndedTasks(object):
    """The last ``remember`` tasks that ended: who answered each and the servers it was
    sent to, so that a later answer for a task id says what it is (:meth:`why`)."""

    def __init__(self, remember):
        self.remember = remember
        self._ended = collections.OrderedDict()     # task id -> (answered by, sent to)

    def add(self, task_id, answered_by, sent_to=()):
        """``answered_by``: the server whose answer ended the task (NO_SERVER: none did);
        ``sent_to``: the servers it was sent to."""
        self._ended[task_id] = (answered_by, frozenset(sent_to))
        while len(self._ended) > self.remember:
            self._ended.popitem(last=False)

    def __len__(self):
        return len(self._ended)

    def why(self, task_id, server):
        """An answer from ``server`` for an ended task: OUTRUN (another copy of it was
        answered first), DUPLICATE (answered already, and not a copy's answer), LATE (it
        failed) or UNKNOWN (not remembered)."""
        if task_id not in self._ended:
            return UNKNOWN
        answered_by, sent_to = self._ended[task_id]
        if answered_by == NO_SERVER:
            return LATE
        return OUTRUN if server != answered_by and server in sent_to else DUPLICATE


class Pending(object):
    """A task in flight: its request, check context, and the attempts made so far."""
    __slots__ = ('task_id', 'stamp', 'request', 'context', 'started', 'attempts', 'deadline',
                 'hedged', 'open', 'not_resent')

    def __init__(self, task_id, stamp, request, context, started):
        self.task_id, self.stamp, self.request, self.context = task_id, stamp, request, context
        self.started, self.attempts, self.deadline = started, [], started
        self.hedged = False
        self.not_resent = None  # why its last failed attempt went nowhere else (None: it did)
        self.open = set()       # servers of attempts not ended yet (no answer, no deadline)

    def attempt(self, server, now, observer=None, kind=None, order=None):
        """An attempt at ``server``, chosen from ``order``, starts ``now``
        (``observer.started(server, kind, first, order)``: ``first`` for the task's first
        attempt)."""
        self.attempts.append((server, now))
        self.open.add(server)
        if observer is not None:
            observer.started(server, kind, len(self.attempts) == 1, order)

    def end(self, server, rtt=None, observer=None):
        """The attempt at ``server`` ended, once: ``observer.ended(server, rtt)``; None
        for every attempt still open."""
        for each in list(self.open) if server is None else [server]:
            if each in self.open:
                self.open.discard(each)
                if observer is not None:
                    observer.ended(each, rtt)

    def hedge_due(self, now, delay):
        """Whether a hedged copy of this task goes now: once, when its only attempt is
        older than ``delay(server)`` s (None: not known yet); a task re-sent meanwhile
        is not hedged."""
        if self.hedged:
            return False
        first, sent = self.attempts[0]
        if len(self.attempts) == 1:
            wait = delay(first)
            if wait is None or now < sent + wait:
                return False
        self.hedged = True
        return len(self.attempts) == 1

    def hedge_at(self, delay):
        """When :meth:`hedge_due` will say yes (None: not by itself: hedged already,
        re-sent, or ``delay`` not known yet)."""
        if self.hedged or len(self.attempts) != 1:
            return None
        first, sent = self.attempts[0]
        wait = delay(first)
        return None if wait is None else sent + wait

    def servers(self):
        """The servers this task was sent to."""
        return frozenset(s for s, _ in self.attempts)

    def sent_at(self, server):
        return next((t for s, t in reversed(self.attempts) if s == server), None)

    def unanswered(self, kind, why):
        """How it ended without an answer: failed, ``why``, the servers it was sent to and,
        when an attempt failed with no other after it, why there was none."""
        return self.outcome(kind, NO_SERVER, False, '%s (%d attempts: servers %s%s)' % (
            why, len(self.attempts), ', '.join(str(s) for s, _ in self.attempts),
            '; not sent again: %s' % self.not_resent if self.not_resent else ''), None)

    def outcome(self, kind, answered_by, ok, error, rtt):
        """How it ended (``rtt`` None: no answer)."""
        return Outcome(self.task_id, kind, self.stamp, self.attempts[0][0], answered_by, ok,
                       error, rtt, len(self.attempts))
