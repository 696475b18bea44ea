"""A node's diagnostics at its stop (ros/diagnostics.py): an update that meets the closed
/diagnostics topic while the node shuts down ends quietly; at any other time it is raised.
A status that raises is published as an error, with a throttled line: raised, it would end
rospy's timer thread, and with it every status of the node."""

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
    diag.updater, diag.before, diag.news, diag._news_seen = ClosedUpdater(), None, None, None
    return diag


class Counting(object):
    """An Updater whose period has not passed: what is published, and how."""
    period, last_time = 1.0, rospy.Time(100)

    def __init__(self):
        self.calls = []

    def update(self):
        self.calls.append('update (nothing due)')

    def force_update(self):
        self.calls.append('published')


def test_news_is_published_at_the_next_tick_not_the_next_period(monkeypatch):
    monkeypatch.setattr(rospy, 'is_shutdown', lambda: False)
    monkeypatch.setattr(rospy.Time, 'now', staticmethod(lambda: rospy.Time(100.25)))
    diag, news, befores = diagnostics(), [5], []
    diag.updater, diag.news, diag._news_seen = Counting(), lambda: news[0], 5
    diag.before = lambda: befores.append(1)
    diag._update(types.SimpleNamespace())
    news[0] = 6                                   # a robot left a server out
    diag._update(types.SimpleNamespace())
    diag._update(types.SimpleNamespace())
    assert diag.updater.calls == ['update (nothing due)', 'published', 'update (nothing due)']
    assert befores == [1]                         # its statuses made anew first


def test_an_update_on_the_closed_topic_at_the_stop_is_quiet(monkeypatch):
    states = iter([False, True])          # shutting down while it updates
    monkeypatch.setattr(rospy, 'is_shutdown', lambda: next(states))
    diagnostics()._update(types.SimpleNamespace())


def test_an_update_that_fails_while_the_node_runs_is_raised(monkeypatch):
    monkeypatch.setattr(rospy, 'is_shutdown', lambda: False)
    with pytest.raises(rospy.ROSException):
        diagnostics()._update(types.SimpleNamespace())


class Recording(object):
    """diagnostic_updater's Updater, keeping the tasks added to it."""

    def __init__(self):
        self.tasks = {}

    def add(self, name, run):
        self.tasks[name] = run


def test_a_status_that_raises_is_an_error_status_not_the_end_of_the_timer(monkeypatch):
    import diagnostic_updater
    lines = []
    monkeypatch.setattr(rospy, 'logerr_throttle', lambda period, text: lines.append(text))
    monkeypatch.setattr(rospy, 'get_name', lambda: '/robot1')
    diag = Diagnostics.__new__(Diagnostics)
    diag.updater, diag.names = Recording(), set()
    diag.add('selection', lambda: {}['server'])
    stat = diag.updater.tasks['selection'](diagnostic_updater.DiagnosticStatusWrapper())
    assert (stat.level, stat.message) == (2, "status failed: KeyError('server')")
    assert len(lines) == 1 and "/robot1: status 'selection' failed" in lines[0]
    assert 'KeyError' in lines[0]
