"""``node.unregister``: a topic closed by its last handle gives its epoll descriptor back at
once, not at the garbage collector's next full collection (no master needed: rospy makes
and closes topics without one)."""

import gc

import pytest
import rospy
from std_msgs.msg import String

from server_select.core.util.procs import epoll_descriptors as epolls
from server_select.ros.node import unregister


@pytest.fixture
def no_collection():
    """The garbage collector off, as it mostly is for a long-lived node's old objects."""
    gc.disable()
    yield
    gc.enable()
    gc.collect()


def test_publishers_and_subscribers_made_and_dropped_leave_no_descriptor(no_collection):
    before = epolls()
    for i in range(10):
        unregister(rospy.Publisher('/renewed_%d' % (i % 2), String, queue_size=1))
        unregister(rospy.Subscriber('/heard_%d' % (i % 2), String, lambda msg: None))
    assert epolls() == before
    for i in range(3):       # rospy's own unregister, for contrast: one left per topic
        rospy.Publisher('/renewed', String, queue_size=1).unregister()
    assert epolls() == before + 3


def test_a_topic_another_handle_still_uses_keeps_its_poller(no_collection):
    kept = rospy.Publisher('/shared', String, queue_size=1)
    unregister(rospy.Publisher('/shared', String, queue_size=1))
    assert not kept.impl.closed and not kept.impl.connection_poll.poller.closed
    kept.impl.check()      # rospy's periodic check still polls it
    unregister(kept)
    assert kept.impl is None
