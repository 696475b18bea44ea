import pytest

from server_select.core.ranking.policy import Policy
from server_select.core.ranking.rank import NO_SERVER, rank_servers
from server_select.core.ranking.window import LatencyWindow, PairStats


def stats(**means):
    return dict((int(k[1:]), PairStats(m, 0 if m is None else 5, 0)) for k, m in means.items())


def test_ranks_by_mean_lowest_first():
    r = rank_servers(stats(s1=0.030, s2=0.010, s3=0.020))
    assert r.ranking == [2, 3, 1]
    assert r.selected == 2
    assert r.means == [0.010, 0.020, 0.030]
    assert r.counts == [5, 5, 5]
    assert r.excluded == []


def test_ties_go_to_the_lower_server_id_whatever_the_input_order():
    pair_stats = {7: PairStats(0.01, 1, 0), 3: PairStats(0.01, 1, 0), 5: PairStats(0.01, 1, 0)}
    assert rank_servers(pair_stats).ranking == [3, 5, 7]


def test_servers_without_successful_sample_are_excluded():
    r = rank_servers(stats(s1=None, s2=0.005, s3=None))
    assert r.ranking == [2]
    assert r.excluded == [1, 3]


def test_no_candidate_selects_no_server():
    r = rank_servers(stats(s1=None, s2=None))
    assert r.selected == NO_SERVER
    assert r.ranking == [] and r.excluded == [1, 2]


def test_window_and_ranking_together_stale_server_drops_out():
    w = LatencyWindow(5.0)
    selected = {}
    for t in range(15):
        w.add(1, 2, float(t), True, 0.005)
        # server 1 is the fastest until it dies at t=5; after that its probes fail
        w.add(1, 1, float(t), t < 5, 0.001)
        selected[t] = rank_servers(w.robot_stats(1, [1, 2], float(t) + 0.5))
    assert [selected[t].selected for t in range(5, 9)] == [1, 1, 1, 1]
    # the last good sample (t=4) is a full window old at t=9: server 1 drops out
    assert selected[9].selected == 2 and selected[9].excluded == [1]


def choose(ranking, current, hysteresis):
    """The paper's rule with ``~hysteresis`` (policy ``mean`` with that margin)."""
    return Policy('mean', margin=hysteresis).choose(ranking, current)


def test_choose_without_hysteresis_is_the_best():
    r = rank_servers(stats(s1=0.0101, s2=0.0100))
    assert choose(r, 1, 0.0) == 2


def test_choose_keeps_current_within_hysteresis():
    r = rank_servers(stats(s1=0.0101, s2=0.0100))
    assert choose(r, 1, 0.001) == 1
    assert choose(r, 1, 0.00005) == 2
    assert choose(r, None, 0.001) == 2


def test_choose_leaves_a_current_server_that_dropped_out():
    r = rank_servers(stats(s1=None, s2=0.0100))
    assert choose(r, 1, 1.0) == 2
    assert choose(rank_servers(stats(s1=None)), 1, 1.0) == NO_SERVER


@pytest.mark.parametrize('n', [1, 2, 10, 100])
def test_ranking_is_sorted_and_complete(n):
    import random
    rnd = random.Random(n)
    pair_stats = dict((s, PairStats(rnd.choice([None, rnd.random()]), 1, 0)) for s in range(n))
    r = rank_servers(pair_stats)
    assert sorted(r.ranking + r.excluded) == list(range(n))
    assert r.means == sorted(r.means)
