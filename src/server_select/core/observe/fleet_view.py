"""What ``rosrun server_select top`` shows: the fleet now, from its own topics (no rospy).

:class:`FleetView` hears what the fleet publishes (task reports, flags, probe samples,
server announcements, log lines) and what the viewer's own probes of the servers say
(their load), each with the time it was heard, and :meth:`FleetView.lines` renders the
view at a moment as text lines: per robot its server, the flag's ranking, its round trip
there, tasks per second, failures and its last switch with the reason its log gave; per
server whether it is up, its load, tasks per second and the robots on it; and alerts (a
server gone, a robot deciding alone, messages ignored).
"""

import collections
import re

WINDOW = 10.0       # s over which rates are counted
GONE_AFTER = 2.0    # s without a good probe answer (or a task) after which a server is gone
#                     (at once when its newest probe failed)
ALERTS = 8          # newest alerts shown

Load = collections.namedtuple('Load', 'queued in_service workers utilization')

# log lines of the fleet that say something an operator wants to see (robot nodes' own
# wording: server_select.nodes.robot, ros.senders, ros.prober)
_SWITCH = re.compile(r'robot (\d+): (?:\S+ )?tasks go to server (\d+) now \((.*)\)')
_ALONE = re.compile(r'robot (\d+): no fresh flag')
_IGNORED = re.compile(r'^(.*?): ignored (.*?) published by (\S+)')


class _Robot(object):
    __slots__ = ('server', 'ranking', 'flagged', 'reason', 'tasks', 'switch', 'rtt', 'alone')

    def __init__(self):
        self.server, self.ranking, self.flagged, self.reason = None, [], None, ''
        self.tasks = collections.deque()       # (time, ok, answered by)
        self.switch = None                     # (time, from, to, why)
        self.rtt = {}                          # server -> its newest good round trip
        self.alone = False


class _Server(object):
    __slots__ = ('seen', 'failed', 'why', 'load', 'left', 'answers')

    def __init__(self):
        self.seen = self.failed = None          # newest good / failed probe of the viewer
        self.why, self.load, self.left = '', None, False
        self.answers = collections.deque()      # times it answered a task


class FleetView(object):
    """The fleet as heard so far (not thread-safe: one caller feeds and renders)."""

    def __init__(self, window=WINDOW, gone_after=GONE_AFTER):
        self.window, self.gone_after = window, gone_after
        self.robots = collections.defaultdict(_Robot)
        self.servers = collections.defaultdict(_Server)
        self.alerts = collections.deque(maxlen=ALERTS)
        self._gone = set()
        self.first = None       # when the view first heard anything (rates count from it)

    def _heard(self, now):
        if self.first is None or now < self.first:
            self.first = now

    # -- what is heard --------------------------------------------------------------------

    def task(self, robot, server, answered_by, ok, now):
        """A task report: first sent to ``server``, answered by ``answered_by``."""
        self._heard(now)
        r = self.robots[robot]
        if server is not None and server >= 0:
            if r.server is not None and server != r.server and (
                    r.switch is None or r.switch[0] < now - 1.0 or r.switch[2] != server):
                why = r.reason if r.flagged == server else ''
                r.switch = (now, r.server, server, why)
            r.server = server
        r.tasks.append((now, ok, answered_by))
        if ok and answered_by is not None and answered_by >= 0:
            self.servers[answered_by].answers.append(now)

    def flag(self, robot, server, ranking, now, reason=''):
        """A flag: ``server`` selected for ``reason`` (the robot's own words when it
        chooses per task)."""
        self._heard(now)
        r = self.robots[robot]
        r.ranking, r.flagged, r.reason, r.alone = list(ranking), server, reason, False
        if r.switch is not None and r.switch[2] == server and not r.switch[3] and reason:
            r.switch = r.switch[:3] + (reason,)

    def sample(self, robot, server, ok, rtt, now):
        self._heard(now)
        if ok:
            self.robots[robot].rtt[server] = rtt

    def probe(self, server, ok, load, now, why=''):
        """The viewer's own probe of ``server``: ``load`` a :data:`Load` when answered."""
        self._heard(now)
        s = self.servers[server]
        if ok:
            s.seen, s.load, s.left = now, load, False
            if server in self._gone:
                self._gone.discard(server)
                self.alerts.append((now, 'server %d is back' % server))
        else:
            s.failed, s.why = now, why

    def announcement(self, server, lease, now):
        self._heard(now)
        s = self.servers[server]
        if lease <= 0:
            s.left = True
            self._gone.add(server)
            self.alerts.append((now, 'server %d left the fleet (clean shutdown)' % server))

    def log(self, text, now):
        """A line of the fleet's log (warnings and the robots' switch lines)."""
        self._heard(now)
        m = _SWITCH.search(text)
        if m:
            r = self.robots[int(m.group(1))]
            r.switch = (now, r.server, int(m.group(2)), m.group(3))
            return
        m = _ALONE.search(text)
        if m:
            self.robots[int(m.group(1))].alone = True
            self.alerts.append((now, 'robot %s decides alone (no fresh flag)' % m.group(1)))
            return
        m = _IGNORED.search(text)
        if m:
            self.alerts.append((now, '%s ignored %s from %s' % m.groups()))

    # -- what is shown --------------------------------------------------------------------

    def gone(self, server, now):
        """Whether ``server`` is gone: it left, its newest probe failed, or no good probe
        answer for a while."""
        s = self.servers[server]
        if s.left:
            return True
        if s.failed is not None and (s.seen is None or s.failed > s.seen):
            return True
        return s.seen is not None and now - s.seen > self.gone_after

    def update(self, now):
        """Forget what is older than the window; alert on servers that went."""
        for r in self.robots.values():
            while r.tasks and r.tasks[0][0] < now - self.window:
                r.tasks.popleft()
        for server, s in self.servers.items():
            while s.answers and s.answers[0] < now - self.window:
                s.answers.popleft()
            if self.gone(server, now) and server not in self._gone:
                self._gone.add(server)
                self.alerts.append((now, 'server %d gone: %s' % (
                    server, s.why or 'no answer for %.3g s' % self.gone_after)))

    def lines(self, now, clock=None, title='server_select top'):
        """The view at ``now`` as lines of text (``clock(t)`` formats an alert's time)."""
        self.update(now)
        clock = clock or (lambda t: '%+.0f s' % (t - now))
        # rates over the window, or over what was heard of it (a view of 5 s: over 5 s)
        span = min(self.window, max(1.0, now - self.first if self.first is not None
                                    else self.window))
        up = sum(1 for s in self.servers if not self.gone(s, now))
        out = ['%s: %d servers (%d up), %d robots; rates over %.3g s'
               % (title, len(self.servers), up, len(self.robots), span), '',
               '%-6s %-7s %-12s %8s %8s %7s  %s'
               % ('ROBOT', 'SERVER', 'RANKING', 'RTT ms', 'TASKS/s', 'FAILED', 'LAST SWITCH')]
        for robot in sorted(self.robots):
            r = self.robots[robot]
            rtt = r.rtt.get(r.server)
            failed = sum(1 for _, ok, _ in r.tasks if not ok)
            switch = '-' if r.switch is None else '%.0f s ago, %s -> %s%s' % (
                now - r.switch[0], r.switch[1] if r.switch[1] is not None else '-',
                r.switch[2], ': ' + r.switch[3] if r.switch[3] else '')
            out.append('%-6d %-7s %-12s %8s %8.1f %7d  %s' % (
                robot, '-' if r.server is None else r.server,
                ' '.join(str(s) for s in r.ranking[:4]) or '-',
                '-' if rtt is None else '%.1f' % (1e3 * rtt), len(r.tasks) / span, failed,
                switch + (' (alone)' if r.alone else '')))
        out += ['', '%-6s %-6s %7s %10s %6s %8s  %s'
                % ('SERVER', 'STATE', 'QUEUED', 'IN SERVICE', 'UTIL', 'TASKS/s', 'ROBOTS')]
        for server in sorted(self.servers):
            s = self.servers[server]
            load = s.load
            on = [str(r) for r in sorted(self.robots) if self.robots[r].server == server]
            out.append('%-6d %-6s %7s %10s %6s %8.1f  %s' % (
                server, 'GONE' if self.gone(server, now) else 'up',
                '-' if load is None else load.queued,
                '-' if load is None else '%d/%d' % (load.in_service, load.workers),
                '-' if load is None else '%.2f' % load.utilization,
                len(s.answers) / span, ' '.join(on) or '-'))
        out += ['', 'ALERTS'] + (['%s  %s' % (clock(t), text) for t, text in self.alerts]
                                 or ['(none)'])
        return out
