"""A robot's own ranking, sent to the manager (``~sample_stream view``, fleet profile)."""

import threading

import rospy

from server_select.core.config import names
from server_select.core.ranking.rank import view_key
from server_select.core.util.lasting import Lasting
from server_select.msg import RobotRanking
from server_select.ros.graph import Liveness, hearing
from server_select.ros.node import fleet
from server_select.ros.routing import DEAF_GRACE, made_anew
from server_select.ros.seal import SealedPublisher


class RankingSender(object):
    """Publishes ``selection.view()`` on ``robot_rankings`` when what the manager needs of
    it changes (:func:`~server_select.core.ranking.rank.view_key`: the servers ranked, those
    left out, the policy's pick from the flagged server), checked whenever a sample may
    have changed it, and every ``1/rate`` s regardless (a restarted manager, fresh means,
    the order below the pick). With ``coalesce`` (the robot's prober calls :meth:`flush`
    once per batch of probe answers), a sample only marks it to be checked: a round's
    answers cost one ranking, not one each (30 servers: 34 samples a second).

    ``manager()`` names the node that must hear the rankings (None: unknown). A manager
    that is up and has not been connected to them for DEAF_GRACE s gets the publisher made
    anew, so that it connects again: rospy's subscriber connects once, and a connection
    lost as it is made (two of the master's updates at once) is never made again, which
    left a robot unflagged for good."""

    def __init__(self, robot_id, selection, policy, rate, manager=lambda: None):
        self.robot_id, self.selection, self.policy = robot_id, selection, policy
        self.period = 1.0 / rate
        self.manager = manager
        self._deaf = Lasting(DEAF_GRACE)
        self._alive = Liveness(period=DEAF_GRACE)
        self._lock = threading.Lock()
        self._key = None
        self._dirty = False
        self.coalesce = False
        self.sent = 0
        self.pub = self.timer = None

    def start(self):
        self.pub = self._publisher()
        self.selection.on_change = self.changed
        self.timer = rospy.Timer(rospy.Duration(self.period), self._tick)

    @staticmethod
    def _publisher():
        return SealedPublisher(fleet(names.RANKINGS_TOPIC), RobotRanking, queue_size=10,
                               tcp_nodelay=True)

    def _tick(self, _event):
        self.send(True)
        self.repair()

    def repair(self):
        """Make the publisher anew when the manager, up, has not heard it for DEAF_GRACE s
        (asked once a period; the master asked at most once a grace period)."""
        node = self.manager()
        if node is None or self.pub is None:
            return
        deaf = node not in hearing(self.pub)
        if not self._deaf.held(node, deaf) or not self._alive(node):
            return
        with self._lock:
            self.pub, _ = made_anew(self.pub, self._publisher, [node])
        rospy.logwarn_throttle(60.0, 'robot %d: %s has not heard our rankings for %g s: '
                               'publishing them anew so that it connects again'
                               % (self.robot_id, node, DEAF_GRACE))

    def changed(self):
        """A sample may have changed the robot's ranking."""
        if self.coalesce:
            self._dirty = True
        else:
            self.send(False)

    def flush(self):
        """Check the ranking once for the samples since the last check."""
        if self._dirty:
            self._dirty = False
            self.send(False)

    def send(self, always):
        if self.pub is None:
            return
        with self._lock:
            ranking = self.selection.view()
            key = view_key(ranking, self.policy, self.selection.flag_selects())
            if key == self._key and not always:
                return
            self._key = key
            self.selection.viewed(key[2])
            chooses = self.policy.per_task and ranking.selected in ranking.ranking
            msg = RobotRanking(robot_id=self.robot_id, ranking=ranking.ranking,
                               mean_latency=ranking.means, error=ranking.errors,
                               sample_count=ranking.counts, excluded=ranking.excluded,
                               wait=[float('nan') if w is None else w for w in ranking.waits]
                               if any(w is not None for w in ranking.waits) else [],
                               selected=ranking.selected if chooses else 0,
                               reason=ranking.reason if chooses else '')
            msg.header.stamp = rospy.Time.now()
            self.pub.publish(msg)
            self.sent += 1

    def shutdown(self):
        if self.timer is not None:
            self.timer.shutdown()
