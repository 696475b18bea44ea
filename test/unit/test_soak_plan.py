"""The soak's schedule and scenario: seeded, every kind, one at a time (the short one in
waves), link outages."""

import os
import random

import pytest

from server_select.soak import plan
from server_select.testbed.scenario import Scenario


def test_a_full_soak_has_every_kind_at_least_twice_one_at_a_time():
    faults = plan.schedule(1800, random.Random(3))
    kinds = [f.kind for f in faults]
    assert all(kinds.count(kind) >= 2 for kind in plan.KINDS)
    for before, after in zip(faults, faults[1:]):
        assert after.at >= before.at + before.length + before.bound
    assert faults[-1].at + faults[-1].length + faults[-1].bound <= 1800 - plan.TAIL[False]


def test_the_same_seed_gives_the_same_schedule_and_another_another():
    assert plan.schedule(1800, random.Random(5)) == plan.schedule(1800, random.Random(5))
    assert plan.schedule(1800, random.Random(5)) != plan.schedule(1800, random.Random(6))


def test_a_short_soak_fits_every_kind_once_and_a_too_short_one_says_what_it_needs():
    needed = plan.needed(1, short=True)
    faults = plan.schedule(needed, random.Random(1), repeats=1, short=True)
    assert sorted(f.kind for f in faults) == sorted(plan.KINDS)
    with pytest.raises(ValueError, match='soak of %.0f s at least' % plan.needed(2)):
        plan.schedule(600, random.Random(1), repeats=2)


def test_a_link_outage_cuts_every_link_of_its_server_for_its_length():
    faults = [plan.Fault('link_down', 2, 100.0, 10.0, 5.0),
              plan.Fault('link_down', 3, 200.0, 10.0, 5.0)]
    scenario = Scenario(plan.scenario(faults, 300))
    for other in ('manager', 'robot1', 'server1', 'server3'):
        assert scenario.link(other, 'server2', 105.0).down
        assert not scenario.link(other, 'server2', 111.0).down
        assert not scenario.link(other, 'server2', 99.0).down
    assert scenario.link('robot1', 'server3', 205.0).down
    assert not scenario.link('robot1', 'server1', 105.0).down
    assert [h.cpu for h in scenario.of_role('server')] == list(plan.SERVER_SHARES)


def test_every_pass_of_every_rotation_lets_told_and_waiting_nodes_trust_each_other():
    ring = plan.KeyRing(['k1', 'k2', 'k3', 'k4'])
    signed = []
    for _ in range(3):
        for move in ring.passes():
            before = ring.state()
            move()
            after = ring.state()
            assert before[0] in after and after[0] in before, (before, after)
        signed.append(ring.state()[0])
    assert signed == ['k2', 'k3', 'k4']


def test_a_soak_of_some_kinds_repeats_them_as_often_as_they_fit():
    faults = plan.schedule(720, random.Random(1), kinds=('overload',))
    assert {f.kind for f in faults} == {'overload'} and len(faults) == 8
    with pytest.raises(ValueError, match='no fault kind overlaod'):
        plan.schedule(720, random.Random(1), kinds=('overlaod',))


def test_the_key_files_handed_to_nodes_are_absolute_paths(tmp_path, monkeypatch):
    """`make soak` gives a folder relative to the repository; roslaunch starts the nodes
    in ROS_HOME, where that path names nothing."""
    from server_select.soak.run import _keys
    monkeypatch.chdir(tmp_path)
    paths = _keys('results/soak', 2)
    assert all(os.path.isabs(p) and os.path.exists(p) for p in paths), paths


def test_the_short_soak_does_every_kind_once_in_waves_each_server_fault_on_its_own_server():
    faults = plan.schedule(plan.needed(1, short=True), random.Random(4), 1, short=True)
    assert sorted(f.kind for f in faults) == sorted(plan.KINDS)
    waves = {}
    for fault in faults:
        waves.setdefault(fault.at, []).append(fault)
    assert len(waves) == len(plan.WAVES)
    for wave in waves.values():
        servers = [f.target for f in wave if f.kind in plan.SERVER_FAULTS]
        assert len(servers) == len(set(servers))
    times = sorted(waves)
    for before, after in zip(times, times[1:]):     # a wave over, bound included, first
        assert after >= max(f.at + f.length + f.bound for f in waves[before])
