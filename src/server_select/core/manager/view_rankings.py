"""The manager's rankings when robots rank for themselves (``~sample_stream view``; no rospy).

Each robot keeps its own samples exactly as the manager would (the same window, task
memory and ``~fail_fast``: :class:`~server_select.core.manager.sample_rankings.SampleRankings`
for one
robot) and sends its ranking when the servers it ranks, those left out, or the policy's
pick change, and every ``1/~view_rate`` s. The manager then costs O(servers) per *change*
rather than O(1) per *sample*: it scales with robots, not with probes. What only it can
do stays with it: the policy's state per robot, group membership, and the flags a
recorder sees.

A robot's ranking counts for ``stale`` s after it arrived: a robot that went silent
(gone, or cut off) has an empty ranking after that, as a robot whose samples all left
the manager's window had.
"""

import heapq

from server_select.core.ranking.rank import NO_SERVER, Ranking, only
from server_select.core.manager.sample_rankings import Members

EMPTY = Ranking(selected=NO_SERVER, ranking=[], means=[], counts=[], excluded=[], errors=[],
                waits=[])


class ViewRankings(Members):
    """Robots' own rankings in, the same interface as
    :class:`~server_select.core.manager.sample_rankings.SampleRankings` out. Thread-safe."""

    def __init__(self, stale, robots=(), servers=()):
        Members.__init__(self, robots, servers)
        self.stale = float(stale)
        self._views = self._heard   # robot -> (receive time, Ranking of its member servers)
        self._due = []        # heap: (when a robot's view goes stale, robot)

    def take(self, robot, now, ranking):
        """``robot``'s own ranking arrived at ``now``; its servers that are not members
        are left out (the manager then decides: every view may change the policy's pick)."""
        if not self.learn_servers:
            ranking = only(ranking, self._server_set.__contains__)
        with self._lock:
            before = self._views.get(robot)
            if before is None or set(before[1].ranking) != set(ranking.ranking) or \
                    set(before[1].excluded) != set(ranking.excluded):
                self.changes += 1
            self._views[robot] = (now, ranking)
            heapq.heappush(self._due, (now + self.stale, robot))

    def rank(self, robot, now):
        """``robot``'s last ranking, or an empty one when it is older than ``stale``."""
        with self._lock:
            view = self._views.get(robot)
        return view[1] if view is not None and now - view[0] < self.stale else EMPTY

    def departures(self, now):
        """The robots whose ranking went stale since the previous call."""
        robots = set()
        with self._lock:
            while self._due and self._due[0][0] <= now:
                _, robot = heapq.heappop(self._due)
                view = self._views.get(robot)
                if view is not None and view[0] + self.stale <= now:
                    robots.add(robot)
            members = set(self.fixed_robots) if not self.learn_robots else None
        return sorted(r for r in robots if members is None or r in members)

    def forget_server(self, server):
        """``server`` left the fleet: out of every ranking now. The robots that ranked it."""
        robots = []
        with self._lock:
            for robot, (when, view) in list(self._views.items()):
                if server in view.ranking or server in view.excluded:
                    self._views[robot] = (when, only(view, lambda other: other != server))
                    robots.append(robot)
            if robots:
                self.changes += 1
        return sorted(robots)

    def selected(self, robot, server):
        """(The robot tracks its own selected server: nothing to note here.)"""
