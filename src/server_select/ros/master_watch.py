"""Life across a roscore restart: rospy does not register again with a new master.

:class:`MasterWatch` asks the master for its pid every ``period`` s. While it is
unreachable nothing changes (existing connections between nodes keep working). When it
answers with another pid than before, the master was restarted and knows nothing of this
node: the watch registers again every publisher, subscriber and service of the node (what
rospy's ``RegManager`` does once at start), and tells each subscription the publishers the
new master knows, through the node's own ``publisherUpdate`` API.

So that a fleet of many nodes does not ask the master all the time, one node (the
manager) is the *watcher*: it checks often and publishes the master's pid, latched, on
``topic`` (``master_pid``); every other node checks rarely (``~master_check``, jittered)
and at once when it hears a pid it does not know. The watcher's connections to the others
do not need the master, so they carry the news of a restart.
"""

import random
import threading
import xmlrpc.client

import rosgraph
import rospy
from rospy.impl.registration import get_service_manager, get_topic_manager
from std_msgs.msg import UInt32


class MasterWatch(object):
    """Re-registers this node with a restarted master, checking every ``period`` s (a
    ``watcher`` also publishes the pid it sees; another node jitters its period by
    +-20 % and checks at once on news of another pid). ``on_change(what)`` hears
    ``'lost'``, ``'back'`` and ``'restarted'``."""

    def __init__(self, period, on_change=None, watcher=False, topic=None):
        self.period = period if watcher else period * random.uniform(0.8, 1.2)
        self.watcher = watcher
        self.on_change = on_change or (lambda what: None)
        self.master = rosgraph.Master(rospy.get_name())
        self.pid = self.master.getPid()
        self.reachable = True
        self.restarts = 0
        self.topic = topic         # where the watcher tells the pid (None: nowhere)
        self.timer = self.pub = self.sub = None
        self._checking = threading.Lock()

    def start(self):
        if self.topic is not None and self.watcher:
            self.pub = rospy.Publisher(self.topic, UInt32, queue_size=1, latch=True)
            self.pub.publish(UInt32(self.pid))
        elif self.topic is not None:
            self.sub = rospy.Subscriber(self.topic, UInt32, self.on_pid, queue_size=1)
        self.timer = rospy.Timer(rospy.Duration(self.period), self.check)

    def on_pid(self, msg):
        """The watcher's news: another pid than ours is worth a check now."""
        if msg.data != self.pid:
            self.check()

    def check(self, _event=None):
        """One check (from the timer, or on the watcher's news; one at a time)."""
        if not self._checking.acquire(blocking=False):
            return          # one is under way: it will see what this one would
        try:
            self._check()
        finally:
            self._checking.release()

    def _check(self):
        try:
            pid = self.master.getPid()
        except (OSError, rosgraph.MasterError, xmlrpc.client.Error):
            if self.reachable:
                self.reachable = False
                rospy.logwarn('%s: master %s unreachable; existing connections keep working',
                              rospy.get_name(), self.master.master_uri)
                self.on_change('lost')
            return
        if not self.reachable:
            self.reachable = True
            self.on_change('back')
        if pid != self.pid:
            rospy.logwarn('%s: master restarted (pid %d, was %d): registering again',
                          rospy.get_name(), pid, self.pid)
            self.register_again()
            self.pid = pid
            self.restarts += 1
            if self.pub is not None:
                self.pub.publish(UInt32(pid))
            self.on_change('restarted')

    def register_again(self):
        uri = rospy.core.get_node_uri()
        node = xmlrpc.client.ServerProxy(uri)
        tm, sm = get_topic_manager(), get_service_manager()
        for name, data_type in tm.get_publications():
            self.master.registerPublisher(name, data_type, uri)
        for name, data_type in tm.get_subscriptions():
            publishers = self.master.registerSubscriber(name, data_type, uri)
            node.publisherUpdate('/master', name, publishers)
        for name, service_uri in sm.get_services():
            self.master.registerService(name, service_uri, uri)

    def shutdown(self):
        if self.timer is not None:
            self.timer.shutdown()
