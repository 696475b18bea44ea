"""The manager's rankings of every robot's servers, kept at O(1) per sample (no rospy).

Which robots and servers take part is either fixed (``robots`` / ``servers`` lists, the
paper) or learned from the samples themselves (empty lists, the fleet profile): a robot
takes part from its first sample, a server from the first sample of it, and a server
drops out of a robot's ranking once the window holds no sample of it at all (it has left:
no probe of it, good or failed, for a whole window).

A sample can change a robot's flag only if it concerns the selected server, a server
that enters or leaves the ranking, or a server whose mean falls below the selected one's;
:meth:`SampleRankings.add` says so in O(1), and only then need the robot be ranked again.
A server also leaves a ranking without any sample, when its newest good sample leaves the
window: :meth:`SampleRankings.departures` names the robots this happened to (one scheduled
check per pair and window, O(log pairs) each; with a window that keeps a rarely sampled
pair's newest samples, its ``horizon``: sooner only when newer samples push the good one
out, which :meth:`SampleRankings.add` reports).
"""

import heapq
import threading

from server_select.core.ranking.passive import TaskCost
from server_select.core.ranking.rank import NO_SERVER, latency, rank_servers
from server_select.core.ranking.window import LatencyWindow


class Members(object):
    """Which robots and servers take part: fixed lists, or (empty) whoever comes."""

    def __init__(self, robots=(), servers=()):
        self.fixed_robots = list(robots)          # empty: learned
        self.fixed_servers = list(servers)        # empty: learned
        self._robot_set, self._server_set = set(robots), set(servers)
        self.learn_robots, self.learn_servers = not robots, not servers
        self._lock = threading.Lock()
        self._heard = {}          # robot -> what is known of it (a subclass's)
        # how many times a robot's servers, ranked or left out, changed (a subclass that
        # counts them: its manager's statuses say so at once rather than at their period)
        self.changes = 0

    def set_members(self, robots, servers):
        """Fix the robots and servers (a group manager: what the top manager assigned to
        its group; either may be empty). Samples of robots and servers left out are no
        longer taken; a robot left out gets no more flags."""
        with self._lock:
            self.fixed_robots, self.fixed_servers = sorted(robots), list(servers)
            self._robot_set, self._server_set = set(robots), set(servers)
            self.learn_robots = self.learn_servers = False

    def robot_refusal(self, robot):
        """Why samples of ``robot`` are not taken (or None)."""
        if not self.learn_robots and robot not in self._robot_set:
            return 'robot %d is not one of ~robots %s' % (robot, self.fixed_robots)
        return None

    def robots(self):
        """The robots that take part (those heard from, or the fixed list)."""
        with self._lock:
            return list(self.fixed_robots) if not self.learn_robots else sorted(self._heard)

    def heard(self, robot):
        with self._lock:
            return robot in self._heard

    def refusal(self, robot, server):
        """Why a sample of (``robot``, ``server``) is not taken (or None)."""
        if not self.learn_robots and robot not in self._robot_set:
            return self.robot_refusal(robot)
        if not self.learn_servers and server not in self._server_set:
            return 'server %d is not one of ~servers %s' % (server, self.fixed_servers)
        return None


class SampleRankings(Members):
    """Samples in, :class:`~server_select.core.ranking.rank.Ranking` per robot out.
    Thread-safe."""

    def __init__(self, window, robots=(), servers=(), statistic='mean', fail_fast=0,
                 robust=False, task_memory=0.0, keep=0, horizon=None):
        Members.__init__(self, robots, servers)
        self.window = LatencyWindow(window, statistic, robust, keep, horizon)
        # task samples' cost above the probes, remembered (core/ranking/passive.py; 0: off)
        self.cost = TaskCost(task_memory) if task_memory > 0 else None
        self.fail_fast = fail_fast
        self._servers = self._heard               # robot -> set of servers heard for it
        self._selected = {}                       # robot -> server its last flag selected
        self._aware = set()                       # robots whose samples say their wait
        self._last_good = {}                      # (robot, server) -> its newest good sample
        self._due = []      # heap: (when that sample leaves the window, robot, server)

    def add(self, robot, server, now, ok, rtt, probe=True, wait=None, detect=True):
        """Record a sample, a probe's or (``probe`` False) an answered task's (ValueError
        for an impossible round trip; ``wait``: the part of ``rtt`` that is the server's
        wait, from a load-aware robot); True when ``robot``'s flag may change because of
        it (``detect`` False: None, not worked out, for a store nobody watches)."""
        if wait is not None:
            self._aware.add(robot)
        if self.cost is not None:
            rtt = self.cost.enter((robot, server), now, ok, rtt, probe)
            if ok and not probe and robot in self._aware:   # a task's queueing and work
                wait = self.cost.above_probes((robot, server), rtt)
        had_mean, stats = self.window.add(robot, server, now, ok, rtt, wait, detect)
        with self._lock:
            newest = self._last_good.get((robot, server)) if ok else None
            if ok and newest is None:       # (again) in the window: due when this leaves
                heapq.heappush(self._due, (now + self.window.horizon, robot, server))
            if ok and (newest is None or now > newest):
                self._last_good[(robot, server)] = now
            heard = self._servers.get(robot)
            if heard is None:
                heard = self._servers[robot] = set()
            new = server not in heard
            if new:
                heard.add(server)
            selected = self._selected.get(robot, NO_SERVER)
        if not detect:
            return None
        if new or server == selected or had_mean != (stats.mean is not None) or \
                (self.fail_fast and not ok):
            return True
        if stats.mean is None:
            return False
        best = latency(self.window.stats(robot, selected, now, errors=False)) \
            if selected != NO_SERVER else None
        return best is None or latency(stats) < best

    def departures(self, now):
        """The robots of which a server has had its last good sample leave the window since
        the previous call: it leaves their rankings, whether selected or not (what the
        manager's periodic check looks at between full re-rankings)."""
        robots = set()
        with self._lock:
            while self._due and self._due[0][0] <= now:
                _, robot, server = heapq.heappop(self._due)
                newest = self._last_good.get((robot, server))
                if newest is None:
                    continue        # the server left the fleet (forget_server)
                if newest + self.window.horizon <= now:
                    del self._last_good[(robot, server)]    # the next good one re-enters
                    robots.add(robot)
                else:
                    heapq.heappush(self._due, (newest + self.window.horizon, robot, server))
            members = set(self.fixed_robots) if not self.learn_robots else None
        return sorted(r for r in robots if members is None or r in members)

    def forget_server(self, server):
        """``server`` left the fleet: out of every ranking now, not once its samples have
        aged out of the window. The robots that ranked it (to be ranked again)."""
        self.window.forget_server(server)
        with self._lock:
            robots = sorted(r for r, heard in self._servers.items() if server in heard)
            for robot in robots:
                self._servers[robot].discard(server)
                self._last_good.pop((robot, server), None)
        if self.cost is not None:
            for robot in robots:
                self.cost.forget((robot, server))
        return robots

    def servers(self, robot, now):
        """``robot``'s servers: the fixed list, or those with a sample in the window."""
        if not self.learn_servers:
            return list(self.fixed_servers)
        with self._lock:
            heard = sorted(self._servers.get(robot, ()))
        kept = [s for s in heard if self._sampled(self.window.stats(robot, s, now))]
        if len(kept) < len(heard):
            with self._lock:
                self._servers[robot] = set(kept) | (self._servers.get(robot, set())
                                                    - set(heard))
            if self.cost is not None:
                for server in set(heard) - set(kept):
                    self.cost.forget((robot, server))
        return kept

    @staticmethod
    def _sampled(stats):
        """Whether the window holds any sample of the pair, good or failed."""
        return stats.ok_count > 0 or stats.failed_count > 0

    def rank(self, robot, now):
        """``robot``'s ranking now (by the window's statistic, stable sort, ties to the lower
        id)."""
        return rank_servers(self.window.robot_stats(robot, self.servers(robot, now), now),
                            self.fail_fast)

    def selected(self, robot, server):
        """Note the server ``robot``'s last flag selected."""
        with self._lock:
            self._selected[robot] = server
