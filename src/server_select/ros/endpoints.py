"""Server side of routing (:mod:`server_select.ros.routing` has both layouts): a task
kind's endpoint, and a result publisher per robot for the direct layout."""

import collections
import threading
import time

import rospy

from server_select.core.config import names
from server_select.core.util.lasting import Lasting
from server_select.ros import bounded_read
from server_select.ros.graph import hearing, stalled
from server_select.ros.node import fleet, unregister
from server_select.ros.routing import DEAF_GRACE, kind_name, renew
from server_select.ros.seal import SealedPublisher


class ResultRoutes(object):
    """Server side of direct routing: one result publisher per robot.

    A fresh publisher has no subscriber yet (the robot, and any recorder, connect once the
    master tells them), so the server makes a robot's publishers when the robot first
    probes it (:meth:`prepare`, off the probe's path), well before its first task. A
    result for a robot whose publisher has no subscriber yet is handed to one sender
    thread that waits up to ``connect_wait`` s for one (at most ``held`` results wait;
    beyond, they go at once): a worker never waits for a listener, and a robot that is
    gone costs its tasks' work, nothing more. At most ``most`` robots keep a publisher:
    the least recently used one goes for a new robot (a node probing or sending under
    made-up robot ids must not exhaust the server, nor lock out a robot it has not met).
    """

    def __init__(self, topic, msg_type, connect_wait=1.0, most=4096, held=64):
        self.topic, self.msg_type, self.connect_wait = topic, msg_type, connect_wait
        self.most, self.held = most, held
        self._lock = threading.Lock()
        self.pubs = collections.OrderedDict()      # robot -> publisher, oldest use first
        self.evicted = 0
        self._waiting = collections.deque()         # (until, robot, result)
        self.deaf = Lasting(DEAF_GRACE)             # robot -> since its node hears none
        self._wake = threading.Condition(self._lock)
        self._sender = None

    def _pub(self, robot):
        """(the lock held) :meth:`prepare`."""
        pub = self.pubs.get(robot)
        if pub is not None:
            self.pubs.move_to_end(robot)
            return pub
        while len(self.pubs) >= self.most:
            gone, old = self.pubs.popitem(last=False)
            self.deaf.forget(gone)
            unregister(old)
            self.evicted += 1
        pub = self.pubs[robot] = SealedPublisher(
            fleet(names.robot_topic(robot, self.topic)), self.msg_type, queue_size=100)
        return pub

    def prepare(self, robot):
        """The publisher of ``robot``'s results (made now if it is not there yet)."""
        with self._lock:
            return self._pub(robot)

    def cut_off(self, robot, node):
        """Whether ``robot``'s result publisher must be made anew (cheap: asked at each of
        its probes): a connection of it is stalled (:func:`~server_select.ros.graph.stalled`),
        or the robot's ``node`` (None: not asked) has not been connected to it for
        DEAF_GRACE s. rospy's subscriber connects when the master names a publisher, and
        not again once that connection ends (reset, or closed just after the master's
        word): the robot would hear none of this server's results while its probes are
        answered."""
        with self._lock:
            pub = self.pubs.get(robot)
            deaf = pub is not None and node is not None and \
                self.deaf.held(robot, node not in hearing(pub))
        return deaf or (pub is not None and bool(stalled(pub)))

    def renew(self, robot, node):
        """Make ``robot``'s result publisher anew if a connection of it is stalled or its
        ``node`` does not hear it, so that the robot connects again; the nodes cut off."""
        with self._lock:
            pub = self.pubs.get(robot)
            deaf = [node] if None not in (pub, node) and node not in hearing(pub) else []
            return renew(self.pubs, robot, lambda: self._pub(robot), deaf)

    def publish(self, robot, result):
        """Send ``result`` to ``robot`` now, or (no subscriber yet) by the sender thread
        once one connects, within ``connect_wait`` s; never blocks."""
        with self._lock:
            pub = self._pub(robot)
            if pub.get_num_connections() or len(self._waiting) >= self.held:
                pub.publish(result)
                return
            self._waiting.append((time.monotonic() + self.connect_wait, robot, result))
            if self._sender is None:
                self._sender = threading.Thread(target=self._send_held, daemon=True,
                                                name='held results')
                self._sender.start()
            self._wake.notify()

    def _send_held(self):
        """The results waiting for their robot's subscriber, each sent once it connects
        or at its time (rospy drops it if nobody listens by then)."""
        with self._lock:
            while not rospy.is_shutdown():
                now = time.monotonic()
                for entry in list(self._waiting):
                    until, robot, result = entry
                    pub = self.pubs.get(robot)
                    if pub is None or pub.get_num_connections() or now >= until:
                        self._waiting.remove(entry)
                        if pub is not None:
                            pub.publish(result)
                self._wake.wait(0.005 if self._waiting else 1.0)


class ServerEndpoint(object):
    """Server side of one task kind: tasks from the broadcast topic and, with ``direct``,
    from this server's own topic too. A task addressed to this server goes to
    ``submit(endpoint, task, direct)`` (the server's workers), which calls ``handle(task)``
    for its result and :meth:`reply` with it; each result goes back the way its task came.
    Tasks addressed to another server are dropped here."""

    def __init__(self, server_id, kind, handle, direct, submit, queue_size=100, rehearse=None):
        self.server_id, self.kind, self.handle = server_id, kind, handle
        self.rehearse = rehearse or (lambda task: False)
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
        # rospy's own read size (64 KiB): with reads of 16 MiB, as image subscribers are
        # often given, a flood of large tasks grew a server's memory several-fold, for no
        # throughput gained
        self.subs = [rospy.Subscriber(topic, kind.task_type, self.on_task, callback_args=direct,
                                      queue_size=queue, tcp_nodelay=True)
                     for topic, direct in topics]
        for sub in self.subs:
            bounded_read.limit(sub.resolved_name, kind.max_bytes())

    def prepare(self, robot):
        """Make ``robot``'s result publisher (direct routing; nothing otherwise)."""
        if self.direct is not None:
            self.direct.prepare(robot)

    def cut_off(self, robot, node):
        """ResultRoutes.cut_off (direct routing; False otherwise)."""
        return self.direct is not None and self.direct.cut_off(robot, node)

    def renew(self, robot, node):
        """ResultRoutes.renew (direct routing; [] otherwise)."""
        return self.direct.renew(robot, node) if self.direct is not None else []

    def held_bytes(self, task):
        """About the memory ``task`` holds while it waits (its kind's estimate)."""
        return self.kind.held_bytes(task)

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
            self.direct.publish(task.robot_id, result)
        else:
            self.pub.publish(result)

    @property
    def topics(self):
        return [sub.resolved_name for sub in self.subs]
