"""The scenario suite's pure parts: replicated robots, figures and ratios."""

import collections
import os

import pytest

from server_select.testbed.bag_analysis import Flag, Report
from server_select.testbed.scenario import Scenario, ScenarioError
from server_select.testbed.runner import RunOptions
from server_select.testbed.suite_scenario import (expand, launch_args, replica_id, robot_params,
                                                  scenario_path, scenario_robot_args)
from server_select.testbed import suite_report

DATA = {'name': 't', 'duration': 60,
        'hosts': {'manager': {'role': 'manager'}, 'server1': {'role': 'server', 'id': 1},
                  'server2': {'role': 'server', 'id': 2}, 'robot1': {'role': 'robot', 'id': 1}},
        'default': {'delay': 5},
        'links': {'robot1 server1': [{'at': 0, 'delay': 1}, {'at': 30, 'delay': 9}]}}


def test_every_variant_gets_a_copy_of_each_robot_with_its_links():
    data, owners = expand(DATA, ['oracle', 'paper'])
    assert owners == {11: ('oracle', 1), 21: ('paper', 1)}
    s = Scenario(data)
    assert sorted(h.id for h in s.of_role('robot')) == [11, 21]
    for rid in (11, 21):
        assert [s.nearest_server(rid, t) for t in (0, 29, 30)] == [1, 1, 2]
    assert 'robot1' not in data['hosts'] and 'robot1' in DATA['hosts']   # a copy
    with pytest.raises(ScenarioError):
        replica_id(1, 10)


def test_a_variant_may_put_its_robots_on_hosts_like_a_busy_pi():
    from server_select.testbed.suite import VARIANTS
    variants = ['fleet', 'fleet_pi3_busy']
    data, owners = expand(DATA, variants, dict((v, VARIANTS[v].host) for v in variants))
    s = Scenario(data)
    plain, pi = s.host_for('robot', 11), s.host_for('robot', 21)
    assert (plain.cpu, plain.busy) == (None, 0.0)
    assert (pi.cpu, pi.cpu_period, pi.memory, pi.busy) == (0.10, 10.0, 1024, 0.5)
    assert owners[21] == ('fleet_pi3_busy', 1) and s.nearest_server(21, 30) == 2


def test_launch_args_and_scenario_files_are_the_packages():
    assert {'policy', 'passive', 'fail_fast'} <= launch_args('manager.launch')
    assert {'hedge', 'policy', 'passive'} <= launch_args('robot.launch')
    assert Scenario.load(scenario_path('near_equal')).name == 'near_equal'


def report(t, robot, ok=True, rtt=0.01):
    return Report(t, robot, int(t * 10), ok, rtt if ok else float('nan'), 1, 1, '', 1)


def test_a_scenarios_robot_args_win_over_the_runs_task_rate_and_timeout():
    """config/sim/mixed_kinds.yaml's robots send 5 sort tasks a second on the testbed as in
    the simulator (its task_rate once made the suite stop: given twice)."""
    options = RunOptions(task_rate=2.0, task_timeout=3.0, start_delay=10.0)
    params = robot_params({'policy': 'least_latency', 'task_rate': 1.0}, options,
                          {'task_rate': 5, 'frame_rate': 0.4, 'robot_index': 0})
    assert params == {'policy': 'least_latency', 'task_rate': 5, 'task_timeout': 3.0,
                      'start_delay': 10.0, 'frame_rate': 0.4, 'robot_index': 0}
    assert robot_params({}, options, {})['task_rate'] == 2.0


def test_the_simulators_camera_is_a_folder_of_one_frame_on_the_testbed():
    args = scenario_robot_args({'image_source': 'frames', 'frame_rate': 0.4}, 12.5)
    assert os.listdir(args['image_source']) == ['face.png']
    assert args['frame_rate'] == 0.4 and args['sweep_start'] == '12.500000'


def test_figures_count_failed_tasks_at_the_timeout_and_switches_per_minute():
    reports = [report(t, 11) for t in range(10, 70)] + [report(40.5, 11, ok=False)]
    reports[0] = reports[0]._replace(attempts=2)          # hedged or re-sent once
    flags = [Flag(t, 11, 1 if t < 40 else 2, [], []) for t in range(0, 70)]
    changes = [(38.0, 11, 2)]
    f = suite_report.figures(reports, flags, [11], changes, 10.0, 70.0, 2.0)
    assert (f.tasks, f.failed) == (61, 1)
    assert f.mean == pytest.approx((60 * 0.01 + 2.0) / 61)
    assert f.switches == pytest.approx(1.0)      # one switch in 60 s, one robot
    assert (f.reaction, f.missed) == (2.0, 0)
    assert f.extra == pytest.approx(1.0 / 61)
    assert suite_report.flag_switches(flags, 50.0, 70.0) == 0


def test_ratios_are_to_the_oracle_with_the_same_routing_and_median_over_runs():
    F = suite_report.Figures
    run = collections.OrderedDict([
        ('oracle', F(10, 0, 0.010, 0.020, 0, None, None, 0)),
        ('oracle_fleet', F(10, 0, 0.008, 0.016, 0, None, None, 0)),
        ('paper', F(10, 0, 0.011, 0.030, 2.0, 1.0, 2.0, 0)),
        ('fleet', F(10, 1, 0.010, 0.020, 0.5, 0.5, 0.5, 0))])
    rel = suite_report.ratios([run])[0]
    assert rel['paper'] == pytest.approx((1.1, 1.5))
    assert rel['fleet'] == pytest.approx((1.25, 1.25))
    rows = suite_report.scenario_rows([run, run, run])
    assert rows[2][:6] == ['paper', 3, '10 (10-10)', '0 (0-0)', '11.00 (11.00-11.00)',
                           '1.100 (1.100-1.100)']
    table = suite_report.targets_table({'near_equal': [run]})
    assert '| near_equal | mean | <= 1.05 | 1.250 | no (by +0.200) |' in table
    assert '| near_equal | switches | <= 2 | 0.500 | yes |' in table


def test_the_search_scenario_follows_the_robots_sweep():
    import yaml
    from server_select.testbed import sweep
    from server_select.testbed.suite_scenario import scenario_robot_args
    from server_select.vision.search import SearchWorld
    area = scenario_path('search_sweep').replace('suite/search_sweep.yaml', 'search_area.yaml')
    data = sweep.scenario(area, duration=40.0)
    s = Scenario(data)
    where = sweep.positions(SearchWorld.load(area), 2, 100.0)[0]
    for t in (5.0, 17.5, 31.0):           # the nearest server is the nearest in the area
        x, y = where(t)
        nearest = min(sweep.SERVERS, key=lambda p: (p[1] - x) ** 2 + (p[2] - y) ** 2)[0]
        assert s.nearest_server(1, t) == nearest
    assert len(set(s.nearest_server(1, t) for t in range(40))) >= 2     # it moves
    shipped = yaml.safe_load(open(scenario_path('search_sweep')))
    args = scenario_robot_args(shipped['suite']['robot_args'], 1234.5)
    assert args['sweep_start'] == '1234.500000' and args['image_source'].startswith('search:/')
    assert args['image_source'].endswith('config/search_area.yaml')


def test_a_variant_is_compared_with_the_oracle_of_its_routing_and_its_hosts():
    from server_select.testbed.suite_report import reference
    every = ['oracle', 'oracle_fleet', 'oracle_pi3_busy', 'oracle_fleet_pi3_busy', 'paper',
             'fleet', 'paper_pi3_busy', 'fleet_pi3_busy']
    assert [reference(v, every) for v in every[4:]] == [
        'oracle', 'oracle_fleet', 'oracle_pi3_busy', 'oracle_fleet_pi3_busy']
    # without an oracle on Pi hosts in the run: the plain one of the same routing
    assert reference('fleet_pi3_busy', ['oracle', 'oracle_fleet', 'fleet_pi3_busy']) == \
        'oracle_fleet'
    assert reference('fleet', ['oracle', 'fleet']) == 'oracle'


def test_every_oracle_variant_follows_the_oracles_flags():
    """An oracle variant's robots must take the oracle's flags: a robot whose rule
    chooses per task (the fleet profile's least_latency) treats flags as a record only, and
    would be one more copy of the fleet's own rule, not the bound."""
    from server_select.core.ranking.policy import Policy
    from server_select.core.settings import default
    from server_select.testbed.suite import VARIANTS
    oracles = [(n, v) for n, v in VARIANTS.items() if v.mode == 'oracle']
    assert len(oracles) == 4
    for name, variant in oracles:
        kind = variant.params.get('policy', default('policy', variant.profile))
        assert not Policy(kind).per_task, (name, kind)
