import pytest

from server_select.core.config import names
from server_select.core.config.params import (ParamError, parse_fixed_server, parse_id,
                                              parse_id_list, parse_members, parse_mode,
                                              parse_node_names, parse_non_negative,
                                              parse_positive)


@pytest.mark.parametrize('value, expected', [
    ([1, 2, 3], [1, 2, 3]), ('1,2,3', [1, 2, 3]), ('1 2 3', [1, 2, 3]), ('[1, 2, 3]', [1, 2, 3]),
    (' 3 , 1 ', [3, 1]), (4, [4]), ('4', [4]), (['5', 6], [5, 6]),
])
def test_id_lists(value, expected):
    assert parse_id_list('~servers', value) == expected


@pytest.mark.parametrize('value', ['', '[]', [], 'a,b', '1,x', [1.5], [-1], '1,1', None, True,
                                   [True]])
def test_bad_id_lists(value):
    with pytest.raises(ParamError) as info:
        parse_id_list('~servers', value)
    assert '~servers' in str(info.value)


@pytest.mark.parametrize('value', [-1, '-1', 'one', 1.0, None, False])
def test_bad_ids(value):
    with pytest.raises(ParamError):
        parse_id('~robot_id', value)


@pytest.mark.parametrize('value, expected', [(1, 1.0), ('2.5', 2.5), (0.1, 0.1)])
def test_positive(value, expected):
    assert parse_positive('~probe_rate', value) == expected


@pytest.mark.parametrize('value', [0, -1, 'fast', None, float('nan'), float('inf'), True])
def test_non_positive_rates_are_rejected(value):
    with pytest.raises(ParamError) as info:
        parse_positive('~probe_rate', value)
    assert '~probe_rate' in str(info.value)


def test_positive_integer():
    assert parse_positive('~task_size', 1000, integer=True) == 1000
    assert parse_positive('~task_size', '1000', integer=True) == 1000
    for bad in (10.5, 0, '1e3x'):
        with pytest.raises(ParamError):
            parse_positive('~task_size', bad, integer=True)


def test_non_negative():
    assert parse_non_negative('~hysteresis', 0) == 0.0
    for bad in (-0.1, 'x', float('inf'), None):
        with pytest.raises(ParamError):
            parse_non_negative('~hysteresis', bad)


def test_modes():
    assert parse_mode('~mode', 'select') == 'select'
    assert parse_mode('~mode', 'fixed') == 'fixed'
    with pytest.raises(ParamError) as info:
        parse_mode('~mode', 'random')
    assert 'random' in str(info.value)


def test_fixed_server_must_be_listed():
    assert parse_fixed_server('~fixed_server', 2, [1, 2, 3], 'fixed') == 2
    assert parse_fixed_server('~fixed_server', '3', [1, 2, 3], 'fixed') == 3
    with pytest.raises(ParamError) as info:
        parse_fixed_server('~fixed_server', 4, [1, 2, 3], 'fixed')
    assert 'not in servers' in str(info.value)
    with pytest.raises(ParamError):
        parse_fixed_server('~fixed_server', '', [1, 2, 3], 'fixed')
    assert parse_fixed_server('~fixed_server', '', [1, 2, 3], 'select') is None
    # only the fixed mode uses it: a robot that learns its servers may be given one
    assert parse_fixed_server('~fixed_server', 1, [], 'select') == 1


@pytest.mark.parametrize('value, expected', [('', []), ([], []), ('[]', []), (' ', []),
                                             ('3,1', [3, 1]), ([2], [2])])
def test_member_lists_may_be_empty(value, expected):
    assert parse_members('~servers', value) == expected


@pytest.mark.parametrize('value, expected', [('', []), ([], []), (None, []),
                                             ('/rec', ['/rec']), ('/a, b', ['/a', 'b']),
                                             (['/a', '/b'], ['/a', '/b'])])
def test_node_name_lists_may_be_empty(value, expected):
    assert parse_node_names('~report_listeners', value) == expected


def test_node_name_lists_are_names():
    with pytest.raises(ParamError, match='list of names'):
        parse_node_names('~report_listeners', [1, 2])


def test_member_lists_refuse_what_id_lists_refuse():
    with pytest.raises(ParamError, match='duplicate'):
        parse_members('~servers', '1,1')


@pytest.mark.parametrize('service, expected', [
    ('/latency_S3', 3), ('/latency_S12', 12), ('/fleet/latency_S3', None),
    ('/latency_S', None), ('/latency_S03', None), ('/latency_S3x', None), ('/other', None)])
def test_probe_services_name_their_server(service, expected):
    assert names.probe_server_id(service, '/') == expected


def test_probe_services_in_a_fleet_namespace():
    assert names.probe_server_id('/fleet/latency_S4', '/fleet/') == 4
    assert names.probe_server_id('/latency_S4', '/fleet/') is None


def test_a_path_with_a_tilde_is_the_users_home(monkeypatch):
    """roslaunch passes ``fleet_key:=~/.ros/robot.key`` as it is: the node expands it."""
    from server_select.core.config.params import parse_path
    monkeypatch.setenv('HOME', '/home/pi')
    assert parse_path('~fleet_key', '~/.ros/robot.key') == '/home/pi/.ros/robot.key'
    assert parse_path('~fleet_key', '/etc/fleet.key') == '/etc/fleet.key'
    assert parse_path('~image_source', 'search:a.yaml') == 'search:a.yaml'
    with pytest.raises(ParamError, match='expected a string'):
        parse_path('~fleet_key', [1])


def test_a_typo_in_any_case_gets_its_did_you_mean():
    from server_select.core.config.params import nearest
    assert nearest('robot_Id', ['robot_id', 'robots']) == 'robot_id'
    assert nearest('duraton', ['duration', 'output']) == 'duration'
    assert nearest('TASK_RATE', ['task_rate', 'frame_rate']) == 'task_rate'
    assert nearest('zzz', ['task_rate']) is None
