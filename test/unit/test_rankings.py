"""The manager's rankings: same answers as ranking everything on every sample, O(1) triggers."""

import random

import pytest

from server_select.core.ranking.policy import Chooser, Policy
from server_select.core.ranking.rank import NO_SERVER, rank_servers
from server_select.core.manager.sample_rankings import SampleRankings
from server_select.core.settings import PARAMS, PROFILES, default


def test_a_robot_is_ranked_as_the_paper_ranks_it():
    r = SampleRankings(5.0, robots=[1], servers=[1, 2, 3])
    for t, server, rtt in [(0.0, 1, 0.004), (0.1, 2, 0.002), (0.2, 3, 0.003)]:
        r.add(1, server, t, True, rtt)
    ranking = r.rank(1, 0.5)
    assert (ranking.selected, ranking.ranking) == (2, [2, 3, 1])
    assert r.rank(1, 5.15).ranking == [3]       # the first two left the window


def test_fixed_lists_refuse_others_learned_lists_take_whoever_comes():
    fixed = SampleRankings(5.0, robots=[1], servers=[1, 2])
    assert 'robot 7' in fixed.refusal(7, 1) and 'server 9' in fixed.refusal(1, 9)
    assert fixed.refusal(1, 2) is None
    learned = SampleRankings(5.0)
    assert learned.refusal(7, 9) is None and learned.robots() == []
    learned.add(7, 9, 0.0, True, 0.001)
    learned.add(3, 9, 0.0, False, 0.0)
    assert learned.robots() == [3, 7] and learned.heard(7) and not learned.heard(4)
    assert learned.rank(3, 0.1).excluded == [9]     # probed, never answered


def test_a_server_with_no_sample_left_in_the_window_has_left():
    r = SampleRankings(5.0)
    r.add(1, 1, 0.0, True, 0.001)
    r.add(1, 2, 0.0, True, 0.002)
    for t in range(1, 9):
        r.add(1, 1, float(t), True, 0.001)        # server 2 is no longer probed
    assert r.servers(1, 8.0) == [1]
    assert r.rank(1, 8.0).excluded == []


def test_a_server_that_left_the_fleet_leaves_every_ranking_at_once():
    r = SampleRankings(1.5, statistic='mean', task_memory=5.0, keep=3, horizon=8.0)
    for robot in (1, 2, 3):
        r.add(robot, 1, 0.0, True, 0.001)
        if robot != 3:
            r.add(robot, 2, 0.0, True, 0.002)
    assert r.forget_server(2) == [1, 2]
    assert r.rank(1, 0.1).ranking == [1] and r.rank(2, 0.1).ranking == [1]
    assert r.forget_server(2) == []
    assert r.departures(100.0) == [1, 2, 3]    # server 1's samples aged out; no error
    r.add(1, 2, 101.0, True, 0.002)            # back in the fleet: ranked again
    assert r.rank(1, 101.0).ranking == [2]


def test_add_says_when_a_flag_may_change():
    r = SampleRankings(5.0)
    assert r.add(1, 1, 0.0, True, 0.002)          # a new server
    assert r.add(1, 2, 0.0, True, 0.004)
    r.selected(1, 1)
    assert not r.add(1, 2, 0.1, True, 0.004)      # still worse than the selected one
    assert r.add(1, 1, 0.2, True, 0.010)          # the selected server itself (mean 6 ms)
    assert r.add(1, 2, 0.3, True, 0.004)          # 4 ms: below the selected one's mean
    assert r.add(1, 3, 0.4, False, 0.0)           # new, even failed
    assert not r.add(1, 3, 0.5, False, 0.0)       # still no mean: nothing changes
    with pytest.raises(ValueError):
        r.add(1, 2, 0.6, True, float('nan'))


def test_departures_name_the_robots_a_server_left_selected_or_not():
    r = SampleRankings(5.0, robots=[1, 2], servers=[1, 2])
    for t in range(3):
        for robot in (1, 2):
            r.add(robot, 1, float(t), True, 0.001)
            r.add(robot, 2, float(t), t == 0, 0.002)      # server 2 dies after t = 0
    r.selected(1, 1)
    r.selected(2, 2)
    assert r.departures(4.99) == []
    assert r.departures(5.0) == [1, 2]    # its last good sample (t = 0) left both windows
    assert r.departures(5.5) == []        # said once
    assert r.rank(1, 5.0).ranking == [1] and r.rank(2, 5.0).ranking == [1]
    assert r.departures(7.5) == [1, 2]    # server 1, never sampled after t = 2
    r.add(1, 2, 8.0, True, 0.002)         # back: it may leave again
    assert r.departures(12.9) == [] and r.departures(13.0) == [1]


def test_a_lazy_manager_ranks_the_same_servers_as_ranking_on_every_sample():
    """Random streams with servers dying and coming back: re-ranking only when add() or
    departures() say so, the ranked servers are at every step those of ranking always."""
    rng = random.Random(5)
    lazy, eager = SampleRankings(2.0), SampleRankings(2.0)
    ranked = []
    alive = dict((s, True) for s in range(1, 6))
    for step in range(6000):
        t = step * 0.05
        if step % 100 == 0:
            alive[rng.randint(1, 5)] = rng.random() > 0.5
        server = rng.randint(1, 5)
        if not alive[server] and rng.random() < 0.5:
            continue            # silent
        ok = alive[server] and rng.random() > 0.05
        rtt = rng.choice([0.001, 0.004]) * (1 + rng.random())
        eager.add(1, server, t, ok, rtt)
        if lazy.add(1, server, t, ok, rtt) | (1 in lazy.departures(t)):
            flag = lazy.rank(1, t)
            ranked = flag.ranking
            lazy.selected(1, flag.selected)
        assert sorted(ranked) == sorted(eager.rank(1, t).ranking), step


def test_updating_only_when_add_says_so_gives_the_flags_of_updating_always():
    """Random streams: a manager that re-ranks only on add() == True publishes the same
    selection as one re-ranking on every sample (the paper's manager)."""
    rng = random.Random(11)
    lazy, eager = SampleRankings(5.0), SampleRankings(5.0)
    lazy_flag = eager_flag = NO_SERVER
    for step in range(4000):
        t = step * 0.05
        server = rng.randint(1, 6)
        ok = rng.random() > 0.05
        rtt = rng.choice([0.001, 0.002, 0.005, 0.3]) * (1 + rng.random())
        if lazy.add(1, server, t, ok, rtt):
            lazy_flag = lazy.rank(1, t).selected
            lazy.selected(1, lazy_flag)
        eager.add(1, server, t, ok, rtt)
        eager_flag = rank_servers(eager.window.robot_stats(1, eager.servers(1, t), t)).selected
        if step % 20 == 0:      # the manager's periodic re-rank catches expiries
            lazy_flag = lazy.rank(1, t).selected
            lazy.selected(1, lazy_flag)
            assert lazy_flag == eager_flag, step
        elif lazy_flag != eager_flag:
            # only an expiry, which the periodic re-rank handles, may differ meanwhile
            assert lazy.rank(1, t).selected == eager_flag, step


def test_profiles_only_name_known_parameters():
    assert PROFILES['paper'] == {}
    for profile in PROFILES.values():
        assert set(profile) <= set(PARAMS)
    assert default('routing') == 'broadcast' and default('routing', 'fleet') == 'direct'
    assert default('sample_stream', 'fleet') == 'view' and default('window') == 5.0
    assert default('policy') == 'mean' and default('policy', 'fleet') == 'least_latency'


def test_a_group_manager_ranks_only_its_members():
    r = SampleRankings(5.0)
    r.set_members([], [])                         # no table from the top manager yet
    assert r.robots() == [] and 'robot 1' in r.refusal(1, 1)
    r.set_members([2, 1], [4, 5])
    assert r.robots() == [1, 2] and r.refusal(1, 4) is None
    assert 'server 7' in r.refusal(1, 7)           # another group's representative
    r.add(1, 4, 0.0, True, 0.002)
    r.add(1, 5, 0.0, True, 0.001)
    assert r.rank(1, 0.1).ranking == [5, 4]
    r.set_members([2], [4, 5])                    # robot 1 moved to another group
    assert r.robots() == [2] and 'robot 1' in r.refusal(1, 4)


def _loaded_server_switches(task_memory, seconds=60.0, seed=3):
    """A manager (the fleet's policy) ranking one robot between server 1, the nearer by
    probes (10 ms) but loaded (its tasks take 25 ms more), and server 2 (12 ms, idle):
    probes at 4 Hz to both, task samples at 10 Hz from the selected server. Returns the
    selections made, one per 0.1 s."""
    rng = random.Random(seed)
    r = SampleRankings(1.5, robust=True, task_memory=task_memory)
    chooser = Chooser(Policy('hysteresis', margin=0.0003, dwell=3.0, z=3.0))
    probe = {1: 0.010, 2: 0.012}
    task = {1: 0.035, 2: 0.012}
    chosen = []
    for i in range(int(seconds * 20)):
        now = i * 0.05
        if i % 5 == 0:
            for server in (1, 2):
                r.add(1, server, now, True, probe[server] + rng.uniform(0, 0.001))
        if i % 2 == 0 and chosen:
            r.add(1, chosen[-1], now, True, task[chosen[-1]] + rng.uniform(0, 0.001),
                  probe=False)
        if i % 2 == 0 and i >= 20:
            chosen.append(chooser.choose(r.rank(1, now), now))
    return chosen


def test_task_memory_keeps_a_robot_off_a_loaded_server_it_has_left():
    def switches(chosen):
        return sum(1 for a, b in zip(chosen, chosen[1:]) if a != b)
    forgetful, remembering = _loaded_server_switches(0.0), _loaded_server_switches(5.0)
    print('switches in 60 s: without task memory %d, with 5 s %d; time on the loaded '
          'server %.0f %% vs %.0f %%' % (switches(forgetful), switches(remembering),
                                         100.0 * forgetful.count(1) / len(forgetful),
                                         100.0 * remembering.count(1) / len(remembering)))
    # without memory the robot goes back each time its task samples leave the window
    assert switches(forgetful) >= 10
    # with it, it tries the loaded server again only after the cost has faded (~20 s)
    assert switches(remembering) <= 6
    assert remembering.count(1) < forgetful.count(1) / 2


def test_task_memory_of_a_server_that_left_is_dropped():
    r = SampleRankings(1.0, task_memory=5.0)
    for t in range(5):
        r.add(1, 1, t * 0.1, True, 0.010)
        r.add(1, 2, t * 0.1, True, 0.012)
        r.add(1, 1, t * 0.1, True, 0.040, probe=False)
    assert r.cost.penalty((1, 1), 0.5) > 0.02
    for t in range(5, 30):
        r.add(1, 2, t * 0.1, True, 0.012)       # server 1 is no longer probed
    assert r.servers(1, 3.0) == [2]
    assert r.cost.penalty((1, 1), 3.0) == 0.0


def test_task_samples_count_their_queueing_as_spread_not_as_a_difference():
    """A load-aware robot's probes see two equal servers; its tasks (one every 3.5 s, a
    third of them queued behind another robot's for 0.1-0.7 s) go to the server it
    selects. A task
    sample's part above the probes is queueing and work: it must widen the margin, not
    prove the selected server slower. With errors from the median absolute deviation
    alone, the robot moved 70 times in these 10 minutes (to the other server, which then
    got the tasks and looked slower in turn); 15 now."""
    rng = random.Random(5)
    policy = Policy('hysteresis', margin=0.0003, z=3.0, dwell=3.0)
    rankings = SampleRankings(1.5, robots=[1], servers=[1, 2], robust=True, task_memory=5.0)
    chooser = Chooser(policy)
    moves, current = 0, 1
    for i in range(4 * 600):
        t = i / 4.0
        for server in (1, 2):
            probe = 0.001 + rng.gauss(0, 0.0001)
            rankings.add(1, server, t, True, probe, wait=0.0)
        if i % 14 == 0:
            queued = rng.uniform(0.1, 0.7) if rng.random() < 0.33 else 0.0
            rankings.add(1, current, t, True, 0.001 + queued, probe=False)
        selected = chooser.choose(rankings.rank(1, t), t, current=current)
        moves += selected != current
        current = selected
    assert moves <= 30, moves
