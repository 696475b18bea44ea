"""What a server's tasks of each kind take (no rospy): the recent work per task, reported
with every probe answer (:class:`~server_select.core.load.work_queue.Load`)."""

import collections
import statistics
import threading
import time

from server_select.core.util.stats import mean_error, median_error

# the standard error of a median of n draws: its variance is 1 / (4 n f(median)^2) for
# large n, sqrt(pi / 2) x sigma / sqrt(n) when the draws are normal
MEDIAN_ERROR = 1.2533
CHECK_SHARE = 0.05   # of a worker's time, at most, that checks of an idle kind take


class ServiceTimes(object):
    """The recent work per task of each kind: the median of the tasks of the last
    ``horizon`` s, at least the newest ``least`` and at most ``keep``, and its standard
    error (thread-safe). A step in the work shows once half of those are new: at 4 tasks
    a second with the third slow one (0.75 s), where the last 20 had needed eleven (2.75
    s: loaded_server's reaction); fewer tasks make a wider error, which the robots count
    as noise.

    A kind none of whose tasks was done in the last ``idle`` s says what the server was, not
    what it is: it reports what its tasks took when each ran alone (no other task of the
    server beside it or waiting, as the next one will), the median of the last ``history``
    such and that median's error, and its next task is measured alone. Not its least median:
    the luck of its best second out of many made a server that robots had just left look
    faster than identical ones still in use, and robots moved to it for nothing. Not what it
    last did: a server left after a burst, whose tasks ran side by side, would report the
    burst until it restarted (nothing sent it a task to learn otherwise); a slowed server's
    few slow tasks before its robots fled move a median of ``history`` little. (Tasks that
    never ran alone: what it last did.) 10 s is the decay time of tower's and Finagle's
    peak-EWMA, which forget a left server alike. A kind whose recent tasks did not run alone
    (a burst) reports the same once none was done for ``horizon`` s: what slowed them is
    gone with it, and the next runs alone. But what a server was is not what it is: a
    slowed one whose robots left said it was fast, and they came back every ``idle`` s to
    slow tasks, and one that recovered was not known to have. So a server nobody sends to
    checks an idle kind (:meth:`due`): it times a copy of its last task, alone, as a task.
    """

    def __init__(self, keep=20, horizon=1.0, least=3, idle=10.0, history=60,
                 clock=time.monotonic):
        if keep < 1 or not 1 <= least <= keep <= history:
            raise ValueError('need 1 <= least <= keep <= history, got %r, %r, %r'
                             % (least, keep, history))
        if idle < horizon:
            raise ValueError('need idle >= horizon, got %r < %r' % (idle, horizon))
        self.keep, self.horizon, self.least, self.idle = keep, float(horizon), least, idle
        self.history = history
        self._clock = clock
        self._lock = threading.Lock()
        self._times = {}
        self._medians = {}
        self._errors = {}
        self._history = {}    # {kind: its last `history` tasks' seconds, run alone}
        self._typical = {}    # {kind: (median, its error) of its history}, until its next task
        self._beside = {}     # {kind: whether a task of its median did not run alone}
        self._checked = {}    # {kind: when a check of it was last begun}

    def add(self, kind, seconds, alone=True):
        """A ``kind`` task took ``seconds``; ``alone``: none ran beside it or waited."""
        now = self._clock()
        with self._lock:
            times = self._times.get(kind)
            if times is None:
                times = self._times[kind] = collections.deque(maxlen=self.keep)
            elif now - times[-1][0] > self.idle:
                times.clear()
            times.append((now, float(seconds), alone))
            if alone:
                history = self._history.get(kind)
                if history is None:
                    history = self._history[kind] = collections.deque(maxlen=self.history)
                history.append(float(seconds))
                self._typical.pop(kind, None)
            while len(times) > self.least and now - times[0][0] > self.horizon:
                times.popleft()
            values = [value for _, value, _ in times]
            self._beside[kind] = not all(ran_alone for _, _, ran_alone in times)
            self._medians[kind] = statistics.median(values)
            self._errors[kind] = MEDIAN_ERROR * mean_error(values)[1]

    def due(self, every):
        """The kinds none of whose tasks was timed or checked in the last ``every`` s (0:
        none), nor in the last 1 / :data:`CHECK_SHARE` of its work: what a server nobody
        sends to times a copy of a task of, to report what one takes now rather than what
        its history says (a slowed server that recovered, or one that slowed).
        :meth:`checking` says a check of one was begun."""
        with self._lock:
            now = self._clock()
            return [kind for kind, times in self._times.items() if every > 0 and
                    now - max(times[-1][0], self._checked.get(kind, times[-1][0])) >=
                    max(every, self._work(kind, now)[0] / CHECK_SHARE)]

    def checking(self, kind):
        """A check of ``kind`` was begun now (its time comes to :meth:`add`)."""
        with self._lock:
            self._checked[kind] = self._clock()

    def _work(self, kind, now):
        """``(seconds, error)`` of ``kind``'s work now (lock held; it was done before)."""
        since = now - self._times[kind][-1][0]
        if since > self.idle or since > self.horizon and self._beside[kind]:
            typical = self._typical.get(kind)
            if typical is None and kind in self._history:
                typical = self._typical[kind] = median_error(self._history[kind])
            return typical or (self._medians[kind], self._errors[kind])
        return self._medians[kind], self._errors[kind]

    def get(self, kind, default=0.0):
        """Seconds of work per task of ``kind`` (``default`` while none was done)."""
        with self._lock:
            return self._work(kind, self._clock())[0] if kind in self._times else default

    def snapshot(self):
        """``{kind: seconds}`` of every kind done so far."""
        with self._lock:
            now = self._clock()
            return {kind: self._work(kind, now)[0] for kind in self._times}

    def errors(self):
        """``{kind: the standard error of its work}`` (0.0 from one task)."""
        with self._lock:
            now = self._clock()
            return {kind: self._work(kind, now)[1] for kind in self._times}


class SenderShares(object):
    """How much of its kind's usual work each sender's tasks take (not thread-safe: the
    :class:`~server_select.core.load.work_queue.WorkQueue` holds its lock). One robot's
    100,000-value sorts and another's 1,000-value ones are both sorts, and frames of one
    size take the same work raw or JPEG-encoded, so the work timed says it, not the bytes:
    the ratio of the sender's moving mean to the kind's. At most ``most`` senders (the
    least recent dropped); 1 for a sender not timed yet."""

    def __init__(self, most=4096, weight=0.2):
        self.most, self.weight = most, weight
        self._senders = collections.OrderedDict()    # (sender, kind) -> its mean work
        self._kinds = {}                             # kind -> every sender's mean work

    def add(self, sender, kind, seconds):
        key = (sender, kind)
        old = self._senders.pop(key, None)
        self._senders[key] = seconds if old is None else old + self.weight * (seconds - old)
        if len(self._senders) > self.most:
            self._senders.popitem(last=False)
        old = self._kinds.get(kind)
        self._kinds[kind] = seconds if old is None else old + self.weight * (seconds - old)

    def ratio(self, sender, kind):
        own, every = self._senders.get((sender, kind)), self._kinds.get(kind)
        return own / every if own is not None and every else 1.0
