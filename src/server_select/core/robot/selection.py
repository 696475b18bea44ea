"""Which servers a robot's next task may go to, best first (no rospy).

``select`` follows the manager's ranking while its flags are fresh, else ranks the servers
by its own probe samples with the manager's policy; with a per-task rule
(:mod:`~server_select.core.peers.balancers`) it asks that rule at each send, the flags for
the record only; ``fixed`` names one server (the paper's baseline); ``local`` works in the
robot. Servers its :class:`~server_select.core.robot.health.ServerHealth` ejected are
skipped while one is usable (:meth:`ServerHealth.order`).
"""

import threading
import time

from server_select.core.peers import balancers
from server_select.core.ranking.policy import Chooser, Policy
from server_select.core.ranking.rank import NO_SERVER, rank_servers
from server_select.core.manager.sample_rankings import SampleRankings
from server_select.core.config.names import LOCAL
from server_select.core.config.params import MODES
from server_select.core.ranking.window import LatencyWindow, check_sample


class Selection(object):
    """The robot's view of where tasks go. Thread-safe."""

    def __init__(self, robot_id, servers, mode, fixed_server=None, health=None, window=5.0,
                 policy=None, manager_timeout=3.0, clock=time.monotonic, statistic=None,
                 passive=False, task_memory=0.0, keep=0, horizon=None, fail_fast=0,
                 rng=None, rule_args=None):
        if mode not in MODES:
            raise ValueError('unknown mode %r' % (mode,))
        self.robot_id, self.servers, self.mode = robot_id, list(servers), mode
        self.fixed_server = fixed_server
        self.health = health
        policy = policy or Policy()
        self.manager_timeout = manager_timeout
        # a rule asked per task, drawing from ``rng`` (None: the ranking decides);
        # ``rule_args``: its own (the league's ablations)
        rule_args = dict(rule_args or {}, window=window)
        self.balancer = balancers.make(policy.kind, clock=clock, rng=rng, **rule_args) \
            if policy.per_task else None
        # its samples as the manager keeps every robot's (its view; None: its rule's own)
        ranked = self.balancer is None or not self.balancer.own_view
        self.rankings = SampleRankings(window, [robot_id], (), statistic or policy.statistic(),
                                       fail_fast, policy.robust, task_memory if passive else
                                       0.0, keep, horizon) if ranked else None
        self.window = self.rankings.window if ranked else None
        # probes only (what a task sample is compared with): a window of its own only
        self.passive = passive     # when task samples share the main one
        self.probes = LatencyWindow(window, keep=keep, horizon=horizon) if passive \
            else self.window
        self._chooser = Chooser(policy)
        self.on_change = None      # on_change(): a sample may have changed view()
        self._clock = clock
        self._lock = threading.Lock()
        self._flag = None          # (receive time, selected, ranking) of the last good one
        self._handed_over = None   # the flag whose selection the own decisions started from
        self._task_servers = None  # where tasks may go (grouped: the group's), None: any

    def on_flag(self, robot_id, server_id, ranking):
        """A flag arrived: None if it is for another robot or taken, else why it is refused."""
        if robot_id != self.robot_id:
            return None
        named = list(ranking) + ([server_id] if server_id != NO_SERVER else [])
        unknown = sorted(set(named) - set(self.servers))
        if unknown:
            return 'names servers %s, not in this robot\'s servers %s' % (unknown, self.servers)
        if server_id != NO_SERVER and server_id not in ranking:
            return 'selects server %d, which its ranking %s lacks' % (server_id, list(ranking))
        with self._lock:
            self._flag = (self._clock(), server_id, list(ranking))
        return None

    def add_server(self, server):
        """A server joined the fleet: a candidate from now on (once it has answered)."""
        with self._lock:
            self.servers += [server] if server not in self.servers else []
        if self.health is not None:
            self.health.add(server)

    def restrict(self, servers):
        """Tasks go only to ``servers`` (grouped: the robot's group's; the others are
        probed for the top manager); None: to any."""
        with self._lock:
            self._task_servers = None if servers is None else set(servers)

    def remove_server(self, server):
        """A server left the fleet: never a candidate again, whatever a flag says."""
        with self._lock:
            self.servers = [s for s in self.servers if s != server]
        if self.health is not None:
            self.health.remove(server)
        if self.rankings is not None:
            self.rankings.forget_server(server)

    def on_sample(self, server, ok, rtt, probe=True, wait=None):
        """One of the robot's own samples: a probe, or (``probe`` False) an answered task
        with ``~passive`` (ValueError for an impossible round trip); ``wait``: the part of a
        load-aware probe's ``rtt`` that is the server's wait. True when the robot's ranking
        may have changed (:meth:`SampleRankings.add`; a rule's own view: always; None:
        nobody watches it, :attr:`on_change` None)."""
        now = self._clock()
        if self.rankings is None:        # a rule with a view of its own
            check_sample(ok, rtt)
            changed = True
        else:
            changed = self.rankings.add(self.robot_id, server, now, ok, rtt, probe, wait,
                                        detect=self.on_change is not None)
        if probe and self.passive:
            self.probes.add(self.robot_id, server, now, ok, rtt)
        if changed and self.on_change is not None:
            self.on_change()
        return changed

    def view(self):
        """The robot's own ranking: by its rule's estimates when it chooses per task with
        a rule that keeps them, else as the manager ranks a robot from its samples (what
        ``~sample_stream view`` sends it); choosing per task, ``selected`` is where its
        tasks go now (when ranked), and the servers it ejected are among those left out."""
        if self.rankings is None:
            ranking = self.balancer.view(self._usable())
            return ranking._replace(excluded=sorted(set(self._servers()) - set(ranking.ranking)))
        ranking = self.rankings.rank(self.robot_id, self._clock())
        last = self.balancer.chosen if self.balancer is not None else None
        if last is not None and last in ranking.ranking:
            ranking = ranking._replace(selected=last, reason=self.balancer.reason)
        return ranking

    def contenders(self):
        """The servers worth probing often, by the robot's rule (every server for a rule
        that keeps no estimates, or for a robot that follows its manager)."""
        if self.balancer is not None:
            return self.balancer.contenders(self._servers())
        return set(self._servers())

    def task_rate(self):
        """The robot's tasks a second lately, as its rule counts them (None: not known)."""
        return self.balancer.task_rate() if self.balancer is not None else None

    def viewed(self, pick):
        """The robot's view was sent picking ``pick``: from now on the samples of ``pick``,
        and those that beat it, are the ones that may change the view."""
        if self.rankings is not None:
            self.rankings.selected(self.robot_id, pick)

    def flag_selects(self):
        """The server the last flag selected, fresh or not (None: no flag yet)."""
        with self._lock:
            return self._flag[1] if self._flag is not None else None

    def probe_latency(self, server):
        """The mean of the robot's probes of ``server`` in the window (None: none; asked
        with ``passive`` only)."""
        return self.probes.stats(self.robot_id, server, self._clock()).mean

    def manager_ranking(self):
        """The fresh manager ranking (selected server first), or None when the last flag is
        older than ``manager_timeout`` s or ranks no server."""
        with self._lock:
            flag = self._flag
        if flag is None or self._clock() - flag[0] > self.manager_timeout or not flag[2]:
            return None
        _, selected, ranking = flag
        return [selected] + [s for s in ranking if s != selected]

    def own_ranking(self):
        """The robot's own ranking from its samples, by the manager's policy."""
        now = self._clock()
        with self._lock:
            servers = list(self.servers)
        ranking = rank_servers(self.window.robot_stats(self.robot_id, servers, now))
        with self._lock:
            # the first own decision after a flag starts from the server the manager
            # selected, which the robot was using: the policy keeps it within its margin
            flag, current = self._flag, None
            if flag is not None and flag is not self._handed_over and flag[1] != NO_SERVER:
                current = flag[1]
            self._handed_over = flag
            selected = self._chooser.choose(ranking, now, current)
        return [s for s in [selected] if s != NO_SERVER] + \
            [s for s in ranking.ranking if s != selected]

    def flagged(self):
        return self._flag is not None      # whether a flag was ever taken

    def deciding_locally(self):
        """Whether a robot that follows the manager has no fresh flag (one that chooses
        per task always decides itself)."""
        return self.mode == 'select' and self.balancer is None and \
            self.manager_ranking() is None

    def candidates(self, kind=None, fresh=None):
        """Where a ``kind`` task may go now, best first: ``[LOCAL]``, ``[fixed server]``,
        the balancer's order of the servers the robot's evidence has not ejected, or the
        (manager's or own) ranking without them (:meth:`ServerHealth.order`)."""
        if self.mode == 'local':
            return [LOCAL]
        if self.mode == 'fixed':
            return [self.fixed_server]
        if self.balancer is not None:     # (``fresh``: :meth:`Balancer.order`'s)
            return self.balancer.order(self._usable(), kind, fresh)
        ranking = self.manager_ranking()
        if ranking is None:
            ranking = self.own_ranking()
        return self.health.order(ranking) if self.health is not None else ranking

    def _usable(self):      # the servers tasks may go to, the ejected ones left out
        servers = self._servers()
        return self.health.order(servers) if self.health is not None else servers

    def _servers(self):
        """The servers tasks may go to (grouped: the group's)."""
        with self._lock:
            return [s for s in self.servers
                    if self._task_servers is None or s in self._task_servers]

    def target(self):
        """The first candidate, or NO_SERVER (a decision: :meth:`heading` makes none)."""
        return (self.candidates() or [NO_SERVER])[0]

    def heading(self, kind=None):
        """Where the next task (of ``kind``; None: of the kind sent most) would go by the
        last decision, without making one (a robot deciding alone decides when it sends):
        the manager's selection while its flags are fresh, else the robot's own; when that
        one is ejected, where the rule sends the next task; NO_SERVER: none."""
        if self.mode != 'select':
            return self.target()
        if self.balancer is not None:
            last = self.balancer.chosen_for.get(kind, self.balancer.chosen)
            if last is None or self.health is None or self.health.usable(last):
                return NO_SERVER if last is None else last
            usable = self._usable()     # (only then: heading() is asked at every probe)
            return last if last in usable else (self.balancer.order(usable, kind) + [NO_SERVER])[0]
        ranking = self.manager_ranking()
        if ranking is None:
            with self._lock:
                ranking = [s for s in [self._chooser.current] if s not in (None, NO_SERVER)]
        ranking = self.health.order(ranking) if self.health is not None else ranking
        return (ranking or [NO_SERVER])[0]

    def ready(self, answered):
        """Whether tasks may start: ``answered`` is the set of servers that have answered a
        probe (fixed mode waits for its server's answer, a per-task rule for one usable
        server's: no first task is sent blind). A per-task rule is not asked."""
        if self.mode == 'fixed':
            return self.fixed_server in answered
        if self.mode == 'select' and self.balancer is not None:
            return bool(set(self._usable()) & set(answered))
        return self.mode == 'local' or bool(self.candidates())
