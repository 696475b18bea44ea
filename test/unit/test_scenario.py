import pytest

from server_select.testbed.scenario import LinkState, Scenario, ScenarioError

HOSTS = {'m': {'role': 'manager'}, 's1': {'role': 'server', 'id': 1},
         's2': {'role': 'server', 'id': 2}, 'r1': {'role': 'robot', 'id': 1}}


def scenario(links=None, **extra):
    data = dict(name='t', duration=100, hosts=HOSTS, default={'delay': 1.0}, links=links or {})
    data.update(extra)
    return Scenario(data)


def test_default_applies_to_unlisted_pairs_both_ways():
    sc = scenario()
    assert sc.link('r1', 's1', 0) == LinkState(1.0, 0.0, 0.0, False)
    assert sc.link('s1', 'r1', 50) == sc.link('r1', 's1', 50)


def test_steps_ramps_down_and_carry_over():
    sc = scenario({'r1 s1': [
        {'at': 0, 'delay': 2, 'jitter': 0.5},
        {'at': 10, 'ramp': 22, 'over': 20},
        {'at': 40, 'down': True},
        {'at': 50, 'down': False, 'delay': 5, 'loss': 0.1}]})
    assert sc.link('r1', 's1', 5) == LinkState(2.0, 0.5, 0.0, False)
    assert sc.link('s1', 'r1', 10).delay == pytest.approx(2.0)
    assert sc.link('r1', 's1', 20).delay == pytest.approx(12.0)
    assert sc.link('r1', 's1', 30).delay == pytest.approx(22.0)
    assert sc.link('r1', 's1', 35) == LinkState(22.0, 0.5, 0.0, False)
    assert sc.link('r1', 's1', 45).down
    assert sc.link('r1', 's1', 45).delay == pytest.approx(22.0)
    assert sc.link('r1', 's1', 60) == LinkState(5.0, 0.5, 0.1, False)


def test_link_before_first_event_is_the_default():
    sc = scenario({'r1-s1': [{'at': 10, 'delay': 7}]})
    assert sc.link('r1', 's1', 5).delay == 1.0 and sc.link('r1', 's1', 10).delay == 7.0


def test_nearest_server_follows_delays_ties_and_down_links():
    sc = scenario({'r1 s1': [{'at': 0, 'delay': 3}, {'at': 10, 'delay': 8},
                             {'at': 20, 'down': True}],
                   'r1 s2': [{'at': 0, 'delay': 5}, {'at': 30, 'down': True}]})
    assert [sc.nearest_server(1, t) for t in (0, 10, 20, 30)] == [1, 2, 2, -1]
    tie = scenario({'r1 s1': [{'at': 0, 'delay': 4}], 'r1 s2': [{'at': 0, 'delay': 4}]})
    assert tie.nearest_server(1, 0) == 1


def test_roles_and_lookup():
    sc = scenario()
    assert sc.manager.name == 'm'
    assert [h.id for h in sc.of_role('server')] == [1, 2]
    assert sc.host_for('robot', 1).name == 'r1'
    with pytest.raises(KeyError):
        sc.host_for('robot', 9)


@pytest.mark.parametrize('links, message', [
    ({'r1 s9': []}, 'unknown host s9'),
    ({'r1': []}, 'not a pair'),
    ({'r1 r1': []}, 'not a pair'),
    ({'r1 s1': [{'delay': 1}]}, 'with "at"'),
    ({'r1 s1': [{'at': 5, 'delay': 1}, {'at': 2, 'delay': 3}]}, 'time order'),
    ({'r1 s1': [{'at': 0, 'ramp': 3}]}, 'needs "over"'),
    ({'r1 s1': [{'at': 0, 'delay': 1, 'ramp': 3, 'over': 1}]}, 'not both'),
    ({'r1 s1': [{'at': 0, 'delay': -1}]}, 'out of range'),
    ({'r1 s1': [{'at': 0, 'loss': 2}]}, 'out of range'),
    ({'r1 s1': [{'at': 0, 'down': 'yes'}]}, 'true or false'),
    ({'r1 s1': [{'at': 0, 'latency': 3}]}, 'unknown keys'),
    ({'r1 s1': [], 's1 r1': []}, 'given twice'),
])
def test_bad_links_are_reported_with_their_place(links, message):
    with pytest.raises(ScenarioError, match=message):
        scenario(links)


@pytest.mark.parametrize('hosts, message', [
    ({}, 'non-empty'),
    ({'s1': {'role': 'server', 'id': 1}}, 'exactly one host must have role manager'),
    ({'m': {'role': 'manager'}, 'x': {'role': 'cloud'}}, "role 'cloud'"),
    ({'m': {'role': 'manager'}, 'x': {'role': 'robot'}}, 'integer id'),
    ({'m': {'role': 'manager'}, 'a': {'role': 'robot', 'id': 1},
      'b': {'role': 'robot', 'id': 1}}, 'two robots with id 1'),
    ({'m': {'role': 'manager'}, 'a-very-long-name': {'role': 'robot', 'id': 1}}, 'alphanumeric'),
])
def test_bad_hosts(hosts, message):
    with pytest.raises(ScenarioError, match=message):
        Scenario({'hosts': hosts})


@pytest.mark.parametrize('key, message', [
    ('duraton', r"\['duraton'\] \(did you mean duration\?\)"),
    ('link', r"\['link'\] \(did you mean links\?\)"),
    ('zzz', 'zzz is not one of name, duration, time_zero, hosts, default, links, suite')])
def test_an_unknown_key_at_top_level_is_named_with_the_nearest_known_one(key, message):
    hosts = {'m': {'role': 'manager'}, 'r1': {'role': 'robot', 'id': 1}}
    with pytest.raises(ScenarioError, match=message):
        Scenario({'hosts': hosts, key: 30})


def test_shipped_scenarios_load(tmp_path):
    import os
    config = os.path.join(os.path.dirname(__file__), '..', '..', 'config')
    for name in ('paper_moving.yaml', 'demo_short.yaml'):
        sc = Scenario.load(os.path.join(config, name))
        assert len(sc.of_role('server')) == 3 and len(sc.of_role('robot')) == 2
    bad = tmp_path / 'bad.yaml'
    bad.write_text('hosts: [1, 2')
    with pytest.raises(ScenarioError, match='bad.yaml'):
        Scenario.load(str(bad))


def test_servers_that_start_late_or_stop_are_not_ranked_meanwhile():
    hosts = dict(HOSTS, s2={'role': 'server', 'id': 2, 'start': 10, 'stop': 30})
    s = scenario({'r1 s2': [{'at': 0, 'delay': 0.5}]}, hosts=hosts)
    assert s.hosts['s2'].start == 10.0 and s.hosts['s2'].stop == 30.0
    assert s.hosts['s1'].start == 0.0 and s.hosts['s1'].stop is None
    assert [s.nearest_server(1, t) for t in (5, 10, 29.9, 30)] == [1, 2, 2, 1]
    assert s.ranking(1, 5) == ([(1.0, 1)], [2])


@pytest.mark.parametrize('spec, message', [
    ({'role': 'server', 'id': 2, 'start': 10, 'stop': 5}, 'stop'),
    ({'role': 'server', 'id': 2, 'start': -1}, 'start'),
    ({'role': 'server', 'id': 2, 'stop': 'later'}, 'stop')])
def test_bad_start_and_stop_times(spec, message):
    with pytest.raises(ScenarioError, match=message):
        scenario(hosts=dict(HOSTS, s2=spec))


def test_the_manager_runs_throughout():
    with pytest.raises(ScenarioError, match='whole scenario'):
        scenario(hosts=dict(HOSTS, m={'role': 'manager', 'stop': 5}))


def test_suite_scenarios_load():
    import glob
    import os
    folder = os.path.join(os.path.dirname(__file__), '..', '..', 'config', 'suite')
    names = sorted(os.path.basename(p) for p in glob.glob(os.path.join(folder, '*.yaml')))
    assert names == ['crossing.yaml', 'hung_server.yaml', 'link_flap.yaml',
                     'loaded_server.yaml', 'near_equal.yaml', 'search_sweep.yaml']
    for name in names:
        assert Scenario.load(os.path.join(folder, name)).duration <= 110


def test_a_hung_server_is_not_ranked_and_its_work_counts_half_each_way():
    hosts = dict(HOSTS, s2={'role': 'server', 'id': 2, 'hang': [[10, 20]],
                            'work': [{'at': 5, 'delay': 25}, {'at': 30, 'delay': 0}]})
    s = scenario({'r1 s2': [{'at': 0, 'delay': 0.5}]}, hosts=hosts)
    assert s.hosts['s2'].hang == ((10.0, 20.0),)
    assert s.hosts['s2'].work == ((5.0, 0.025), (30.0, 0.0))
    # s2 is 0.5 ms away, s1 1 ms: 25 ms of work on s2 from 5 s to 30 s sends the oracle to s1
    assert [s.nearest_server(1, t) for t in (4.9, 5, 10, 19.9, 20, 30)] == [2, 1, 1, 1, 1, 2]
    assert s.ranking(1, 5) == ([(1.0, 1), (13.0, 2)], [])


@pytest.mark.parametrize('spec, message', [
    ({'role': 'server', 'id': 2, 'hang': [[10, 5]]}, 'hang'),
    ({'role': 'server', 'id': 2, 'hang': [10, 20]}, 'hang'),
    ({'role': 'server', 'id': 2, 'work': [{'at': 5}]}, 'work'),
    ({'role': 'server', 'id': 2, 'work': [{'at': 5, 'delay': -1}]}, 'work'),
    ({'role': 'robot', 'id': 2, 'hang': [[1, 2]]}, 'only a server')])
def test_bad_hang_and_work(spec, message):
    with pytest.raises(ScenarioError, match=message):
        scenario(hosts=dict(HOSTS, s2=spec))


def test_a_bad_file_is_one_error_naming_the_file(tmp_path):
    bad = tmp_path / 'bad.yaml'
    bad.write_text('name: x\nduration: abc\nhosts: {}\n')
    with pytest.raises(ScenarioError) as error:
        Scenario.load(str(bad))
    assert str(error.value) == "%s: duration: expected a number, got 'abc'" % bad
    with pytest.raises(ScenarioError) as error:
        Scenario.load(str(tmp_path / 'missing.yaml'))
    assert str(error.value).startswith('%s: ' % (tmp_path / 'missing.yaml'))
    assert '\n' not in str(error.value)


class _Cpu(object):
    """A process's CPU time and the wall clock, advanced by hand: ``stall`` is wall time
    during which the process got no CPU (a quota spent by others)."""

    def __init__(self):
        self.wall = self.cpu = 0.0

    def spin(self):             # each look at the CPU clock costs 0.1 ms of CPU
        self.cpu += 1e-4
        self.wall += 1e-4
        return self.cpu

    def sleep(self, seconds):
        self.wall += seconds


def test_own_work_keeps_its_pace_and_forgets_what_it_could_not_run():
    from server_select.testbed.busy import burn
    t = _Cpu()
    state = {'stalled': False}

    def until():                    # 1 s at its pace, then a 2 s stall, then 1 s more
        if not state['stalled'] and t.wall >= 1.0:
            state['stalled'], t.wall = True, t.wall + 2.0
            state['mark'] = t.cpu
        return t.wall >= 4.0

    used = burn(0.2, until, clock=lambda: t.wall, cpu=t.spin, sleep=t.sleep)
    # the second second runs at 0.2 plus at most 0.05 s of wall time caught up (0.01 s of CPU)
    assert state['mark'] == pytest.approx(0.2, abs=0.002)
    assert used - state['mark'] == pytest.approx(0.2, abs=0.015)
    with pytest.raises(ValueError):
        burn(1.5, lambda: True)


def test_time_zero_is_at_launch_unless_the_scenario_waits_for_its_nodes():
    assert scenario().time_zero == 'launch'
    assert scenario(time_zero='ready').time_zero == 'ready'
    with pytest.raises(ScenarioError, match="time_zero: 'later' is neither launch nor ready"):
        scenario(time_zero='later')
