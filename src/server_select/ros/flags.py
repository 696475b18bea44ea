"""Publishing selection flags: one place builds a SelectionFlag from a ranking."""

import threading

import rospy

from server_select.core.config import names
from server_select.msg import SelectionFlag
from server_select.ros.node import fleet, param
from server_select.ros.seal import SealedPublisher


def flag_topic(robot, stream):
    """The topic ``robot``'s flags reach it on: the shared ``server_select_flag``, or with
    ``~flag_stream`` ``robot`` its own ``robot_<r>/server_select_flag``."""
    return fleet(names.SELECTION_TOPIC if stream == 'shared'
                 else names.robot_topic(robot, names.SELECTION_TOPIC))


class FlagPublisher(object):
    """``server_select_flag`` for many robots, sent when asked or when it changes.

    A robot's flag counts as changed when its selected server or the set of servers it
    ranks differs from the last one published for it. With ``~flag_stream`` ``robot``
    (fleet profile) each flag goes to its robot alone, on the robot's own latched topic
    (a robot that connects late gets its last flag at once), and a copy goes on the shared
    topic, which no robot then hears: it costs a write only for each recorder listening.
    """

    def __init__(self, source, queue_size=100):
        self.source = source     # 'manager', 'oracle': for the log
        self.stream = param('flag_stream')
        self._lock = threading.Lock()
        self._published = {}     # robot -> (selected, frozenset of ranked servers)
        self._own = {}           # robot -> its own topic's publisher (flag_stream robot)
        self.pub = SealedPublisher(fleet(names.SELECTION_TOPIC), SelectionFlag,
                                   queue_size=queue_size)

    def _robot_pub(self, robot):
        """``robot``'s own topic's publisher, advertised at its first flag (one master call,
        made outside the flags' lock: robots that start together do not queue behind it;
        two threads that race both advertise, and rospy shares the topic between them)."""
        pub = self._own.get(robot)
        if pub is None:
            pub = self._own.setdefault(robot, SealedPublisher(
                flag_topic(robot, self.stream), SelectionFlag, queue_size=2, latch=True))
        return pub

    def offer(self, robot, ranking, only_on_change, choose=None, why=None):
        """Publish ``robot``'s flag for ``ranking`` (a
        :class:`~server_select.core.ranking.rank.Ranking`) unless ``only_on_change`` and nothing
        changed; True if published. ``choose(previous)`` picks the server given the one
        published before (None at first), ``why()`` then says why; default: the ranking's
        best, for the ranking's reason. :meth:`selected` then tells the server chosen."""
        ranked = frozenset(ranking.ranking)
        own = self._robot_pub(robot) if self.stream == 'robot' else None
        with self._lock:
            previous, previous_ranked = self._published.get(robot, (None, None))
            selected = choose(previous) if choose else ranking.selected
            if only_on_change and (previous, previous_ranked) == (selected, ranked):
                return False
            self._published[robot] = (selected, ranked)
            reason = why() if why else ranking.reason
            flag = SelectionFlag(robot_id=robot, server_id=selected, ranking=ranking.ranking,
                                 mean_latency=ranking.means, sample_count=ranking.counts,
                                 excluded=ranking.excluded, reason=reason)
            flag.header.stamp = rospy.Time.now()
            if own is not None:
                own.publish(flag)
            self.pub.publish(flag)      # (robot stream: for recorders; free without one)
        if previous != selected:
            rospy.loginfo('%s: robot %d -> server %s (%s; ranking %s, ms %s)', self.source,
                          robot, selected if selected != SelectionFlag.NO_SERVER else 'none',
                          reason or 'the ranking\'s first', ranking.ranking,
                          ['%.2f' % (m * 1e3) for m in ranking.means])
        return True

    def selected(self, robot):
        """The server ``robot``'s last published flag selected (None: no flag yet)."""
        with self._lock:
            return self._published.get(robot, (None, None))[0]
