"""A robot's own ranking (sample_stream view) is checked once per batch of probe answers
when its prober says when a batch ended, and still goes out when it changed."""

import rospy.rostime

from server_select.core.robot.selection import Selection
from server_select.core.ranking.policy import Policy
from server_select.ros.view import RankingSender


class Wire(object):
    def __init__(self):
        self.sent = []

    def publish(self, msg):
        self.sent.append(list(msg.ranking))


def _sender(coalesce):
    rospy.rostime.set_rostime_initialized(True)     # stamps from the wall clock, no master
    clock = [0.0]
    selection = Selection(1, [1, 2, 3], 'select', policy=Policy('mean'), window=1.5,
                          clock=lambda: clock[0])
    sender = RankingSender(1, selection, Policy('mean'), 1.0)
    sender.pub, sender.coalesce = Wire(), coalesce
    selection.on_change = sender.changed
    views = []
    selection.view = (lambda view: lambda: views.append(1) or view())(selection.view)
    return selection, sender, views


def test_a_batch_of_answers_costs_one_check_and_a_change_still_goes_out():
    for coalesce in (False, True):
        selection, sender, views = _sender(coalesce)
        for server, rtt in ((1, 0.003), (2, 0.002), (3, 0.001)):     # one round's answers
            selection.on_sample(server, True, rtt)
        if coalesce:
            assert views == [] and sender.pub.sent == []
            sender.flush()
            sender.flush()                        # nothing new: nothing checked
        print('coalesce %s: %d checks, sent %s' % (coalesce, len(views), sender.pub.sent))
        assert len(views) == (1 if coalesce else 3)
        assert sender.pub.sent[-1] == [3, 2, 1]
