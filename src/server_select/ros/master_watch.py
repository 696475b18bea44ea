"""Life across a roscore restart: rospy does not register again with a new master.

:class:`MasterWatch` polls the master every ``period`` s. While it is unreachable nothing
changes (existing connections between nodes keep working). When it answers with another
pid than before, the master was restarted and knows nothing of this node: the watch
registers again every publisher, subscriber and service of the node (what rospy's
``RegManager`` does once at start), and tells each subscription the publishers the new
master knows, through the node's own ``publisherUpdate`` API.
"""

import xmlrpc.client

import rosgraph
import rospy
from rospy.impl.registration import get_service_manager, get_topic_manager


class MasterWatch(object):
    """Re-registers this node with a restarted master. ``on_change(what)`` hears
    ``'lost'``, ``'back'`` and ``'restarted'``."""

    def __init__(self, period, on_change=None):
        self.period = period
        self.on_change = on_change or (lambda what: None)
        self.master = rosgraph.Master(rospy.get_name())
        self.pid = self.master.getPid()
        self.reachable = True
        self.restarts = 0
        self.timer = None

    def start(self):
        self.timer = rospy.Timer(rospy.Duration(self.period), self.check)

    def check(self, _event=None):
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
