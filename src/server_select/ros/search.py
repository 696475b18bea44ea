"""A robot's part in the cooperative search: targets found in its frames are shared once."""

import collections
import math
import threading

import rospy
from std_msgs.msg import Header

from server_select.core.config import names
from server_select.msg import Detections, FoundTarget
from server_select.ros.graph import publisher_of
from server_select.ros.node import fleet
from server_select.ros.seal import SealedPublisher, seal
from server_select.ros.senders import SenderGate
from server_select.srv import KnownTargets, KnownTargetsResponse
from server_select.vision.search import Found, TargetRegistry


class SearchParticipant(object):
    """Turns detections in this robot's frames into ``found_targets`` records, once each.

    ``world`` (a :class:`~server_select.vision.search.SearchWorld`, or None) places a
    detection on the area map from where the frame was taken; without it, positions are
    frame coordinates. A target within ``merge_radius`` of a known one is not reported
    again, whoever found the first.
    """

    def __init__(self, robot_id, merge_radius, world=None, remember=1000):
        self.robot_id = robot_id
        self.world = world
        self.registry = TargetRegistry(merge_radius)
        self._lock = threading.Lock()
        self._views = collections.OrderedDict()   # task id -> where its frame was taken
        self._remember = remember
        self.found_pub = None
        # with a fleet key, detections and found targets count only when sealed with it
        self.gate = SenderGate('robot %d' % robot_id, 'a node of the fleet')

    def start(self):
        found = fleet(names.FOUND_TARGETS_TOPIC)
        self.found_pub = SealedPublisher(found, FoundTarget, queue_size=100,
                                         subscriber_listener=_OwnFindsToNewcomers(self))
        self.found_sub = rospy.Subscriber(found, FoundTarget, self.on_found, queue_size=100,
                                          tcp_nodelay=True)
        self.detections_sub = rospy.Subscriber(fleet(names.DETECTIONS_TOPIC), Detections,
                                               self.on_detections, queue_size=100,
                                               tcp_nodelay=True)
        self.known_srv = rospy.Service(names.KNOWN_TARGETS_SERVICE, KnownTargets,
                                       self.on_known_targets)

    def remember(self, task_id, where):
        with self._lock:
            self._views[task_id] = where
            while len(self._views) > self._remember:
                self._views.popitem(last=False)

    def on_detections(self, msg):
        if msg.robot_id == self.robot_id and msg.detections and \
                self.gate.admits(msg, 'detections'):
            self.found_in(msg.task_id, [(d.roi.x_offset, d.roi.y_offset, d.roi.width,
                                         d.roi.height, d.label) for d in msg.detections])

    def found_in(self, task_id, boxes):
        """Record the ``(x, y, w, h, label)`` boxes found in the frame of ``task_id``."""
        with self._lock:
            where = self._views.get(task_id)
        for x, y, w, h, label in boxes:
            if self.world is not None and where is not None:
                wx, wy = self.world.to_world(where[0], where[1], (x, y, w, h))
            else:
                wx, wy = x + w / 2.0, y + h / 2.0   # no map: frame coordinates
            found = Found(self.robot_id, task_id, label, wx, wy, rospy.get_time())
            if self.registry.add(found):
                rospy.loginfo('robot %d: found %s at (%.0f, %.0f)', self.robot_id, label, wx, wy)
                self.found_pub.publish(_message(found))

    def on_found(self, msg):
        if msg.robot_id == self.robot_id or not self.gate.admits(msg, 'a found target'):
            return
        if not (math.isfinite(msg.x) and math.isfinite(msg.y)):
            rospy.logwarn_throttle(5.0, 'robot %d: ignored a found target of %s at (%r, %r): '
                                   'not a place' % (self.robot_id, publisher_of(msg), msg.x,
                                                    msg.y))
            return
        if not self.registry.add(Found(msg.robot_id, msg.task_id, msg.label, msg.x, msg.y,
                                       msg.header.stamp.to_sec())) and self.registry.full():
            rospy.logwarn_throttle(5.0, 'robot %d: ignored a found target of %s: %d targets '
                                   'are known, the most kept' % (self.robot_id,
                                                                 publisher_of(msg),
                                                                 self.registry.limit))

    def on_known_targets(self, _request):
        return KnownTargetsResponse(targets=[_message(f) for f in self.registry.all()])

    def own_finds(self):
        """The targets this robot found itself, oldest first."""
        return [f for f in self.registry.all() if f.robot_id == self.robot_id]


class _OwnFindsToNewcomers(rospy.SubscribeListener):
    """A find is published once; a node that subscribes later (a robot started or
    restarted mid-search) is sent this robot's own finds on its new connection alone."""

    def __init__(self, participant):
        super(_OwnFindsToNewcomers, self).__init__()
        self.participant = participant

    def peer_subscribe(self, topic_name, topic_publish, peer_publish):
        for found in self.participant.own_finds():
            peer_publish(seal(_message(found), topic_name))


def _message(found):
    return FoundTarget(header=Header(stamp=rospy.Time.from_sec(found.stamp)),
                       robot_id=found.robot_id, task_id=found.task_id, label=found.label,
                       x=found.x, y=found.y)
