"""How a task ended at the robot (:class:`Outcome`), what an answer did
(:class:`Resolution`), and the constants a ``task_report`` uses (no rospy, no messages:
the unit tests pin the constants equal to ``TaskReport``'s). A task in flight is a
:class:`~server_select.core.flow.attempts.Pending`."""

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
