"""What a robot's task flow does as time passes (no rospy): an attempt's deadline, a
task's timeout, a hedged copy, and when that next happens (a part of
:class:`~server_select.core.flow.task_flow.TaskFlow`)."""

from server_select.core.flow.outcome import LOCAL


class Timing(object):
    """The time-driven half of a :class:`~server_select.core.flow.task_flow.TaskFlow`: it
    uses the flow's lock, pending tasks, clock, timeout, deadlines, hedge, candidates,
    budget and counters."""

    def tick(self):
        """Act on passed deadlines: re-send, or report tasks out of time. Returns the
        Outcomes reported."""
        now = self._clock()
        ended = []
        with self._lock:
            for pending in list(self._pending.values()):
                if now >= pending.started + self.timeout:     # as next_wake has it
                    self._drop(pending)
                    ended.append((pending, 'no result within task_timeout %.3g s'
                                  % self.timeout))
                elif now >= pending.deadline:
                    server, sent = pending.attempts[-1]
                    pending.end(server, now - sent, self._attempts)
                    self._on_failure(server, 'no answer within %.3g s' % (now - sent))
                    if self._gives_way():     # not worth sending again
                        self._drop(pending)
                        ended.append((pending, 'no result within its attempt deadline and '
                                      'a newer task waits'))
                    elif not self._next(pending, stranded=self._silent[server]):
                        # nobody left: wait for any late answer
                        pending.deadline = pending.started + self.timeout
                elif self.hedge is not None and pending.hedge_due(   # the first not blamed
                        now, lambda server: self.deadlines.hedge_seconds(server, self.hedge)):
                    self._next(pending, hedge=True)
        return [self._end(p.unanswered(self.kind, why)) for p, why in ended]

    def next_wake(self):
        """The clock time at which :meth:`tick` next has something to do (an attempt's
        deadline, a task's timeout, a hedge); None while no task is out."""
        hedge = (lambda server: self.deadlines.hedge_seconds(server, self.hedge)) \
            if self.hedge is not None else None
        with self._lock:
            times = [min(p.started + self.timeout, p.deadline) for p in self._pending.values()]
            if hedge is not None:
                times += [t for t in (p.hedge_at(hedge) for p in self._pending.values())
                          if t is not None]
        return min(times) if times else None

    def _next(self, pending, hedge=False, stranded=0):
        """Send ``pending`` to the next candidate it has not tried (a re-send, or a
        ``hedge``); False if there is none. A task with a freshness deadline goes only
        where the load says it can still be done in time. ``stranded``: the attempts sent to
        the server that failed to answer it in time since it last answered anything
        (:meth:`RetryBudget.spend`)."""
        tried = set(s for s, _ in pending.attempts)
        elapsed = self._clock() - pending.started
        order = self._candidates()
        untried = [s for s in order if s not in tried and s != LOCAL
                   and not self.deadlines.too_busy(s, elapsed)]
        if not untried:
            if not hedge:
                pending.not_resent = 'no other server to try (candidates %s)' % (order,)
            return False
        if self.budget is not None and not self.budget.spend(reserve=not hedge,
                                                             stranded=stranded):
            self.unfunded += 1
            if not hedge:
                pending.not_resent = 'the retry budget (%s) is spent' % self.budget.describe()
            return False
        if hedge:
            self.hedged += 1
        else:
            self.resent += 1
        self._attempt(pending, untried[0], order)
        return True

    def _gives_way(self):
        """Whether a newer task, held back, takes a late one's place (counted)."""
        self.superseded += self.newest_wins and self._held
        return self.newest_wins and self._held
