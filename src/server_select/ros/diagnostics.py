"""A node's health on ``/diagnostics`` through ``diagnostic_updater``, once a second, so
that ``rosdiagnostic``, ``rqt_robot_monitor`` and ``rqt_runtime_monitor`` show the fleet
(what each status says: :mod:`server_select.core.observe.health_status`)."""

import traceback

import diagnostic_updater
import rospy

from server_select.core.config.names import LOCAL, NO_SERVER
from server_select.core.observe import health_status
from server_select.ros import params_in_force, seal

PERIOD = 1.0    # s between two statuses (~diagnostic_period, diagnostic_updater's own)


class Diagnostics(object):
    """``add(name, status)`` tasks, each ``status()`` -> ``(level, message, [(key,
    value)])``; published as ``<node>: <name>`` with the node's name as hardware id."""

    def __init__(self):
        # unset, diagnostic_updater would ask the master for it 4 times a second
        params_in_force.write_default('diagnostic_period', PERIOD)
        self.updater = diagnostic_updater.Updater()
        self.updater.setHardwareID(rospy.get_name())
        self.names = set()
        self.timer = None
        self.before = None      # called before each update (a node adding statuses)
        # a count that grows when what a status says may have changed: published at once
        # (a killed server is an ERROR on the manager's status within a tick, not a period)
        self.news = None
        self._news_seen = None

    def add(self, name, status):
        if name in self.names:
            return
        self.names.add(name)

        def run(stat):
            try:
                level, message, values = status()
            except Exception as error:  # raised, it would end rospy's timer: no status again
                rospy.logerr_throttle(10.0, '%s: status %r failed: %s' % (
                    rospy.get_name(), name, traceback.format_exc(limit=4)))
                level, message, values = health_status.ERROR, 'status failed: %r' % error, []
            stat.summary(level, message)
            for key, value in values:
                stat.add(key, str(value))
            return stat
        self.updater.add(name, run)     # (published as "<node>: <name>")

    def start(self):
        self.timer = rospy.Timer(rospy.Duration(PERIOD / 4), self._update)

    def _update(self, _event):
        if rospy.is_shutdown():
            return
        news = self.news() if self.news is not None else None
        force, self._news_seen = news != self._news_seen, news
        if self.before is not None and (force or rospy.Time.now() >= self.updater.last_time
                                        + rospy.Duration(self.updater.period)):
            self.before()
        try:
            if force:
                self.updater.force_update()
            else:
                self.updater.update()
        except rospy.ROSException:      # "publish() to a closed topic": the node stops
            if not rospy.is_shutdown():
                raise

    def shutdown(self):
        if self.timer is not None:
            self.timer.shutdown()


def _since_last(count):
    """``step()`` -> how much ``count()`` grew since the previous step."""
    last = [count()]

    def step():
        now = count()
        grew, last[0] = now - last[0], now
        return grew
    return step


def _server(node, diag):
    busy, done = _since_last(lambda: node.work.busy), \
        _since_last(lambda: node.work.queue.finished)
    diag.add('load', lambda: health_status.server_status(node.work.load(), busy(), done()))


def _robot(node, diag):
    sent = _since_last(lambda: sum(s.flow.sent for s in node.streams))
    failed = _since_last(lambda: sum(s.flow.failed for s in node.streams))
    balancer = node.selection.balancer

    def status():
        target = node.selection.heading()
        return health_status.robot_status(
            None if target in (NO_SERVER, None) else 'the robot itself' if target == LOCAL
            else target,
            balancer.reason if balancer is not None else 'the manager\'s flag', sent(),
            failed(), dict((s, node.health.state(s)) for s in node.robot.servers
                           if not node.health.usable(s)),
            seal.enabled())
    diag.add('selection', status)


def _manager(node, diag):
    def statuses():
        now = rospy.get_time()
        views = {}
        for robot in node.rankings.robots():
            ranking = node.rankings.rank(robot, now)
            views[robot] = (set(ranking.ranking), set(ranking.excluded))
        return health_status.fleet_statuses(views, set().union(
            *[good | bad for good, bad in views.values()]))
    latest = {}

    def before():           # a status per server, added as servers appear
        latest.clear()
        latest.update(statuses())
        for server in latest:
            diag.add('server %d' % server, lambda s=server: latest.get(s, (
                health_status.STALE, 'no robot ranks it any more', [])))
    diag.before = before
    diag.news = lambda: node.rankings.changes


ROLES = {'server': _server, 'robot': _robot, 'manager': _manager}


def start_for(node, role):
    """The statuses of a node of ``role`` on ``/diagnostics`` (None for other roles)."""
    if role not in ROLES:
        return None
    diag = Diagnostics()
    ROLES[role](node, diag)
    diag.start()
    return diag
