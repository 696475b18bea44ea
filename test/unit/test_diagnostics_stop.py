"""A node's diagnostics at its stop (ros/diagnostics.py): an update that meets the closed
/diagnostics topic while the node shuts down ends quietly; at any other time it is raised."""

import types

import pytest
import rospy

from server_select.ros.diagnostics import Diagnostics


class ClosedUpdater(object):
    period, last_time = 1.0, rospy.Time(0)

    def update(self):
        raise rospy.ROSException('publish() to a closed topic')


def diagnostics():
    diag = Diagnostics.__new__(Diagnostics)
    diag.updater, diag.before = ClosedUpdater(), None
    return diag


def test_an_update_on_the_closed_topic_at_the_stop_is_quiet(monkeypatch):
    states = iter([False, True])          # shutting down while it updates
    monkeypatch.setattr(rospy, 'is_shutdown', lambda: next(states))
    diagnostics()._update(types.SimpleNamespace())


def test_an_update_that_fails_while_the_node_runs_is_raised(monkeypatch):
    monkeypatch.setattr(rospy, 'is_shutdown', lambda: False)
    with pytest.raises(rospy.ROSException):
        diagnostics()._update(types.SimpleNamespace())
