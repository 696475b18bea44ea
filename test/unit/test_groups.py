"""Server groups: the table, what a robot probes, and the top manager's assignment."""

import pytest

from server_select.core.fleet.groups import GroupAssigner, parse_groups, probe_set, representatives
from server_select.core.config.params import ParamError

GROUPS = {1: [1, 2, 3], 2: [4, 5, 6], 3: [7]}


@pytest.mark.parametrize('value', [GROUPS, '{1: [1, 2, 3], 2: [4, 5, 6], 3: [7]}',
                                   {'1': '1,2,3', '2': [4, 5, 6], '3': 7}])
def test_groups_from_yaml_or_mapping(value):
    assert parse_groups('~groups', value) == GROUPS


@pytest.mark.parametrize('value, message', [
    ('{1: [1, 2], 2: [2, 3]}', 'server 2 is in groups 1 and 2'), ('[1, 2]', 'mapping'),
    ('{1: []}', 'non-empty'), ('{x: [1]}', 'integer'), ('{1: [1', 'not YAML'), ({}, 'mapping')])
def test_bad_groups_say_why(value, message):
    with pytest.raises(ParamError, match=message):
        parse_groups('~groups', value)


def test_a_robot_probes_its_group_and_every_representative():
    assert representatives(GROUPS) == {1: 1, 4: 2, 7: 3}
    assert probe_set(GROUPS, None) == {1, 4, 7}
    assert probe_set(GROUPS, 2) == {1, 4, 5, 6, 7}
    # probes grow with group size plus number of groups, not with all servers
    big = dict((g, list(range(100 * g, 100 * g + 100))) for g in range(1, 11))
    assert len(probe_set(big, 3)) == 100 + 9


def test_robots_go_to_the_nearest_representative_and_stay_within_the_margin():
    a = GroupAssigner(GROUPS, window=5.0, margin=0.001)
    assert not a.assign(1, 0.0)                     # nothing heard yet
    a.add(1, 2, 0.0, True, 0.0001)                  # not a representative: ignored
    a.add(1, 1, 0.0, True, 0.010)
    a.add(1, 4, 0.0, True, 0.004)
    a.add(1, 7, 0.0, False, 0.0)                    # group 3 unreachable
    assert a.assign(1, 0.1) and a.table() == [(1, 2)]
    a.add(1, 1, 1.0, True, 0.0)                     # group 1 mean 5 ms: nearer by 1 ms ...
    a.add(1, 4, 1.0, True, 0.008)                   # ... group 2 mean 6 ms: not enough
    assert not a.assign(1, 1.1) and a.table() == [(1, 2)]
    a.add(1, 4, 2.0, True, 0.020)                   # group 2 now 10.7 ms
    assert a.assign(1, 2.1) and a.table() == [(1, 1)]
    for t in (3.0, 4.0, 5.0, 6.0, 7.5):
        a.add(1, 4, t, True, 0.002)                 # group 1 leaves the window, 2 is near
    assert a.assign(1, 7.6) and a.table() == [(1, 2)]


def test_ties_go_to_the_lower_group():
    a = GroupAssigner(GROUPS, window=5.0, margin=0.0)
    a.add(5, 4, 0.0, True, 0.003)
    a.add(5, 1, 0.0, True, 0.003)
    assert a.assign(5, 0.0) and a.table() == [(5, 1)]
