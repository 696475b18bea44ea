"""A probe whose handling raises still ends (ros/prober.py): failed, with a log line naming
the server, so the robot probes that server again (a probe left out is never followed by
another)."""

import types
from unittest import mock

from server_select.ros import prober as probing


class Robot(object):
    def __init__(self):
        self.failed, self.answered = [], []

    def probe_failed(self, server, seq, error):
        self.failed.append((server, seq, error))

    def probe_answered(self, server, seq, rtt, load=None):
        self.answered.append((server, seq))


def prober(load_of=None):
    with mock.patch.object(probing, 'keyed', return_value=False):
        made = probing.Prober(1, 0.5, load_of=load_of)
    made.robot = Robot()
    made._request = lambda server, seq, kinds, rates: 'request'
    made.seal.forgery = lambda *args: None
    return made


def test_a_connect_first_probe_that_raises_ends_failed_and_says_which_server():
    made = prober()
    made._proxies[2] = mock.Mock(call_within=mock.Mock(side_effect=TypeError('a bug')))
    with mock.patch('rospy.logerr_throttle') as log:
        made._probe(2, 7, (), ())
    made.shutdown()
    assert made.robot.failed == [(2, 7, 'probe not handled: TypeError: a bug')]
    assert log.call_args[0][1] == 'robot 1: probe of server 2: TypeError: a bug'


def test_an_answer_whose_check_raises_ends_the_probe_failed():
    def unreadable(response):
        raise KeyError('kinds')
    made = prober(load_of=unreadable)
    answer = types.SimpleNamespace(server_id=2, seq=7)
    made._proxies[2] = mock.Mock(call_within=mock.Mock(return_value=(answer, 0.001)))
    with mock.patch('rospy.logerr_throttle'):
        made._probe(2, 7, (), ())
    made.shutdown()
    assert made.robot.failed == [(2, 7, "probe not handled: KeyError: 'kinds'")]
    assert made.robot.answered == []
