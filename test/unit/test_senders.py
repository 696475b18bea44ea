"""Who may publish what: the rule every publisher check uses, and its log throttle."""

import pytest

from support.clock import Clock
from server_select.core.trust.senders import ExpectedSender, Throttle, owned_by


def test_a_node_owns_itself_and_its_namespace_only():
    assert owned_by('/robot1', '/robot1')
    assert owned_by('/robot1/camera', '/robot1')
    assert owned_by('/robot1/camera', '/robot1/')
    assert not owned_by('/robot10', '/robot1')
    assert not owned_by('/robot', '/robot1')


def test_one_expected_node_exact_or_with_its_namespace():
    exact = ExpectedSender('/manager')
    assert exact.refusal('/manager') is None
    assert exact.refusal('/manager/helper') == '/manager'
    assert exact.refusal('/spoofer') == '/manager'
    within = ExpectedSender('/robot1', within=True)
    assert within.refusal('/robot1/helper') is None
    assert within.refusal('/robot12') == '/robot1'


def test_no_expected_node_admits_any():
    assert ExpectedSender().refusal('/anyone') is None
    assert ExpectedSender(lookup=lambda key, refresh: None).refusal('/anyone', 3) is None


def test_a_lookup_is_asked_again_once_when_another_node_sends():
    master = {2: '/server2'}           # what the master says
    known = dict(master)               # what the lookup last looked up
    calls = []

    def lookup(key, refresh):
        calls.append((key, refresh))
        if refresh:
            known.update(master)
        return known.get(key)
    rule = ExpectedSender(lookup=lookup)
    assert rule.refusal('/server2', 2) is None
    assert calls == [(2, False)]
    master[2] = '/server2_restarted'          # restarted under another name
    assert rule.refusal('/server2_restarted', 2) is None
    assert calls[1:] == [(2, False), (2, True)]
    assert rule.refusal('/spoofer', 2) == '/server2_restarted'
    assert rule.refusal('/server2', 2) == '/server2_restarted'


def test_expected_and_lookup_exclude_each_other():
    with pytest.raises(ValueError):
        ExpectedSender('/manager', lookup=lambda key, refresh: None)


def test_a_throttle_writes_one_line_a_period_and_counts_the_rest():
    clock = Clock()
    throttle = Throttle(5.0, clock)
    assert throttle.due() == (True, 0)
    clock.now += 1.0
    assert throttle.due() == (False, 0)
    assert throttle.due() == (False, 0)
    clock.now += 4.0
    assert throttle.due() == (True, 2)
    clock.now += 5.0
    assert throttle.due() == (True, 0)


def test_the_robot_node_pattern_that_would_admit_a_robot_named_otherwise():
    from server_select.core.trust.senders import node_pattern_of
    assert node_pattern_of('/tb3_2/robot2', 2) == '/tb3_{id}/robot{id}'
    assert node_pattern_of('/fleetA/tb3_12/robot', 12) == '/fleetA/tb3_{id}/robot'
    assert node_pattern_of('/tb3_12/robot', 2) is None        # 12 is not 2
    assert node_pattern_of('/spoofer', 1) is None


def test_a_claimed_key_is_the_first_senders_while_it_lives_then_the_next_ones():
    """A robot is known by the id it announces: the first node that sends for robot 2 is
    robot 2, whatever its name; another node is refused while the first answers."""
    living = {'/tb3_2/robot': True, '/robot2': True}
    asked = []

    def alive(node):
        asked.append(node)
        return living.get(node, False)
    rule = ExpectedSender(alive=alive, within=True)
    assert rule.refusal('/tb3_2/robot', 2) is None
    assert rule.refusal('/tb3_2/robot/prober', 2) is None       # a node in its namespace
    assert rule.refusal('/tb3_1/robot', 1) is None              # each key its own claim
    assert asked == []                                          # no look-up while it matches
    assert rule.refusal('/robot2', 2) == '/tb3_2/robot'         # a second claim, refused
    living['/tb3_2/robot'] = False                              # the first one is gone
    assert rule.refusal('/robot2', 2) is None
    assert rule.refusal('/tb3_2/robot', 2) == '/robot2'         # the claim moved
    with pytest.raises(ValueError):
        ExpectedSender('/manager', alive=alive)


def test_one_senders_lines_do_not_hide_anothers_and_all_lines_are_bounded():
    from server_select.core.trust.senders import SenderThrottle
    clock = Clock()
    throttle = SenderThrottle(5.0, lines=3, most=4, clock=clock)
    assert throttle.due(1) == (True, 0)
    assert throttle.due(1) == (False, 0)      # robot 1 again within the period
    assert throttle.due(9) == (True, 0)       # robot 9 named at once all the same
    assert throttle.due(9) == (False, 0)
    assert throttle.due(2) == (True, 0)
    assert throttle.due(3) == (False, 0)      # a 4th line within the period: held
    clock.now += 5.0
    assert throttle.due(1) == (True, 1)       # robot 1's held line counted in its next
    assert throttle.due(3) == (True, 1)
    # made-up senders: 3 lines a period whatever their number, and 4 remembered
    written = sum(throttle.due(1000 + n)[0] for n in range(500))
    assert written == 1 and len(throttle._senders) == 4
