"""Server side of routing (:mod:`server_select.ros.routing` has both layouts): a task
kind's endpoint, and a result publisher per robot for the direct layout."""

import threading
import time

import rospy

from server_select.core.config import names
from server_select.ros.graph import publisher_of, stalled
from server_select.ros.node import fleet
from server_select.ros.routing import kind_name, renew
from server_select.ros.seal import SealedPublisher


class ResultRoutes(object):
    """Server side of direct routing: one result publisher per robot.

    A fresh publisher has no subscriber yet (the robot, and any recorder, connect once the
    master tells them), so the server makes a robot's publishers when the robot first
    probes it (:meth:`prepare`, off the probe's path), well before its first task. A
    result for a robot without a connected publisher still waits up to ``connect_wait`` s
    for one instead of being lost. At most ``most`` robots get a publisher (a node sending
    tasks under made-up robot ids must not exhaust the server): None beyond.
    """

    def __init__(self, topic, msg_type, connect_wait=1.0, most=4096):
        self.topic, self.msg_type, self.connect_wait = topic, msg_type, connect_wait
        self.most = most
        self._lock = threading.Lock()
        self.pubs = {}

    def _pub(self, robot):
        """(the lock held) :meth:`prepare`."""
        pub = self.pubs.get(robot)
        if pub is None and len(self.pubs) >= self.most:
            return None
        if pub is None:
            pub = self.pubs[robot] = SealedPublisher(
                fleet(names.robot_topic(robot, self.topic)), self.msg_type, queue_size=100)
        return pub

    def prepare(self, robot):
        """The publisher of ``robot``'s results (made now if it is not there yet; None
        when ``most`` robots have one already)."""
        with self._lock:
            return self._pub(robot)

    def stalled(self, robot):
        """Whether a connection of ``robot``'s result publisher is stalled
        (:func:`~server_select.ros.graph.stalled`; cheap: asked at each of its probes)."""
        with self._lock:
            pub = self.pubs.get(robot)
        return pub is not None and bool(stalled(pub))

    def renew(self, robot):
        """Make ``robot``'s result publisher anew if a connection of it is stalled, so
        that the robot connects again (``DirectRoute.heard`` says why); the stalled nodes."""
        with self._lock:
            return renew(self.pubs, robot, lambda: self._pub(robot))

    def publish(self, robot, result):
        """Send ``result`` to ``robot``; False when it has no publisher (see ``most``)."""
        pub = self.prepare(robot)
        if pub is None:
            return False
        if not pub.get_num_connections():
            end = time.monotonic() + self.connect_wait
            while not pub.get_num_connections() and time.monotonic() < end \
                    and not rospy.is_shutdown():
                time.sleep(0.005)
        with self._lock:      # (the one renew() may have made since)
            pub = self._pub(robot)
            if pub is not None:
                pub.publish(result)
        return pub is not None


class ServerEndpoint(object):
    """Server side of one task kind: tasks from the broadcast topic and, with ``direct``,
    from this server's own topic too. A task addressed to this server goes to
    ``submit(endpoint, task, direct)`` (the server's workers), which calls ``handle(task)``
    for its result and :meth:`reply` with it; each result goes back the way its task came.
    Tasks addressed to another server are dropped here."""

    def __init__(self, server_id, kind, handle, direct, submit, queue_size=100):
        self.server_id, self.kind, self.handle = server_id, kind, handle
        self.kind_name = kind_name(kind)
        self.submit = submit
        self.direct = ResultRoutes(kind.result_topic, kind.result_type) if direct else None
        self.queue_size = queue_size
        self.pub, self.subs = None, []
        self._busy_field = 'busy' in getattr(kind.result_type, '__slots__', ())
        # an error result is made as the plain message (a numpy_msg view of it, as sort
        # results are, cannot serialize its empty arrays, which are lists)
        base = kind.result_type.__bases__[0]
        self._error_type = base if getattr(base, '_type', None) == kind.result_type._type \
            else kind.result_type

    def start(self):
        kind, queue = self.kind, self.queue_size
        self.pub = SealedPublisher(fleet(kind.result_topic), kind.result_type, queue_size=queue)
        topics = [(fleet(kind.task_topic), False)]
        if self.direct is not None:
            topics.append((fleet(names.server_topic(self.server_id, kind.task_topic)), True))
        self.subs = [rospy.Subscriber(topic, kind.task_type, self.on_task, callback_args=direct,
                                      queue_size=queue, tcp_nodelay=True, buff_size=1 << 24)
                     for topic, direct in topics]

    def prepare(self, robot):
        """Make ``robot``'s result publisher (direct routing; nothing otherwise)."""
        if self.direct is not None:
            self.direct.prepare(robot)

    def stalled(self, robot):
        """ResultRoutes.stalled (direct routing; False otherwise)."""
        return self.direct is not None and self.direct.stalled(robot)

    def renew(self, robot):
        """ResultRoutes.renew (direct routing; [] otherwise)."""
        return self.direct.renew(robot) if self.direct is not None else []

    def on_task(self, task, direct):
        if task.server_id == self.server_id:
            self.submit(self, task, direct)

    def error_result(self, task, why, busy=False):
        """A not-ok result for ``task`` saying ``why`` (``busy``: could not be done in time;
        a result type without the field says so in ``why`` alone)."""
        result = self._error_type(header=task.header, robot_id=task.robot_id,
                                  task_id=task.task_id, server_id=self.server_id, ok=False,
                                  error=why)
        if busy and self._busy_field:
            result.busy = True
        return result

    def reply(self, task, direct, result):
        """Send ``result`` back the way ``task`` came."""
        if direct:
            if not self.direct.publish(task.robot_id, result):
                rospy.logwarn_throttle(5.0, 'server %d: no answer to %s task %d of robot %d '
                                       '(published by %s): already %d robots have result '
                                       'topics here' % (self.server_id, self.kind_name,
                                                        task.task_id, task.robot_id,
                                                        publisher_of(task), self.direct.most))
        else:
            self.pub.publish(result)

    @property
    def topics(self):
        return [sub.resolved_name for sub in self.subs]
