"""Robots that rank for themselves (~sample_stream view): core/manager/view_rankings.py and
core/ranking/rank.py."""

import math

import pytest

from server_select.core.ranking.policy import Policy
from server_select.core.ranking.rank import Ranking, from_view, only, rank_servers, view_key
from server_select.core.manager.sample_rankings import SampleRankings
from server_select.core.robot.selection import Selection
from server_select.core.manager.view_rankings import EMPTY, ViewRankings


def ranking(servers, means, excluded=()):
    return Ranking(selected=servers[0] if servers else -1, ranking=list(servers),
                   means=list(means), counts=[3] * len(servers), excluded=list(excluded),
                   errors=[1e-5] * len(servers), waits=[None] * len(servers))


def test_a_view_is_checked_and_read_as_the_manager_ranks():
    view = from_view([2, 1], [0.001, 0.002], [1e-5, 2e-5], [3, 4], [], [3])
    assert view == Ranking(selected=2, ranking=[2, 1], means=[0.001, 0.002], counts=[3, 4],
                           excluded=[3], errors=[1e-5, 2e-5], waits=[None, None])
    waits = from_view([1], [0.01], [0.0], [1], [float('nan')], []).waits
    assert waits == [None]
    assert from_view([], [], [], [], [], [4]).selected == -1


@pytest.mark.parametrize('bad', [
    ([1, 2], [0.001], [0.0, 0.0], [1, 1], [], []),             # arrays of unequal length
    ([1, 1], [0.001, 0.002], [0.0, 0.0], [1, 1], [], []),      # a server twice
    ([1, 2], [0.001, 0.002], [0.0, 0.0], [1, 1], [], [2]),     # ranked and excluded
    ([1, 2], [0.002, 0.001], [0.0, 0.0], [1, 1], [], []),      # not ascending
    ([1], [float('nan')], [0.0], [1], [], []),                 # not a latency
    ([1], [-1.0], [0.0], [1], [], []),
    ([1], [0.001], [0.0], [1], [0.0, 0.0], []),                # waits of another length
    ([1], [0.001], [float('nan')], [1], [], []),               # not an error
    ([1], [0.001], [0.0], [1], [-1.0], []),                    # not a wait
])
def test_a_view_that_cannot_be_a_ranking_is_refused(bad):
    with pytest.raises(ValueError):
        from_view(*bad)


def test_the_view_key_changes_with_the_servers_the_exclusions_and_the_policys_pick():
    policy = Policy('hysteresis', margin=0.0003)
    a = ranking([1, 2, 3], [0.0010, 0.0011, 0.0012])
    assert view_key(a, policy, 2) == ({1, 2, 3}, set(), 2)     # within the margin: kept
    assert view_key(ranking([1, 2], [0.0010, 0.0020]), policy, 2)[2] == 1
    # the order below the pick is not news; a new best is, when nothing is flagged yet
    assert view_key(a, policy, 1) == view_key(ranking([1, 3, 2], [0.001, 0.0011, 0.0012]),
                                              policy, 1)
    assert view_key(a, policy, None) != view_key(ranking([2, 1, 3], [0.001, 0.0011, 0.0012]),
                                                 policy, None)
    assert view_key(a, policy, 1) != view_key(ranking([1, 2, 3], [0.001, 0.0011, 0.0012], [4]),
                                              policy, 1)
    assert view_key(a, policy, 1) != view_key(ranking([1, 2], [0.001, 0.0011]), policy, 1)


def test_only_keeps_the_wanted_servers_in_order():
    kept = only(ranking([3, 1, 2], [0.001, 0.002, 0.003], [4]), lambda s: s != 3)
    assert (kept.selected, kept.ranking, kept.means, kept.excluded) == \
        (1, [1, 2], [0.002, 0.003], [4])


def test_the_manager_keeps_each_robots_latest_view_until_it_is_stale():
    views = ViewRankings(3.0)
    views.take(1, 10.0, ranking([2, 1], [0.001, 0.002]))
    views.take(2, 10.5, ranking([1], [0.001]))
    assert views.robots() == [1, 2] and views.heard(1) and not views.heard(3)
    assert views.rank(1, 12.9).ranking == [2, 1]
    assert views.departures(12.9) == []
    assert views.rank(1, 13.0) == EMPTY
    assert views.departures(13.6) == [1, 2]
    assert views.departures(20.0) == []                # said once
    views.take(1, 20.0, ranking([1], [0.001]))
    views.take(1, 21.0, ranking([1], [0.001]))         # renewed: stale from 24 on
    assert views.departures(23.5) == [] and views.departures(24.0) == [1]


def test_a_group_manager_takes_only_its_servers_of_a_view():
    views = ViewRankings(3.0)
    views.set_members([1], [4, 5])
    views.take(1, 0.0, ranking([1, 5, 9, 4], [0.001, 0.002, 0.003, 0.004], [6, 4 + 1]))
    kept = views.rank(1, 0.1)
    assert (kept.selected, kept.ranking, kept.excluded) == (5, [5, 4], [5])
    assert views.robot_refusal(2) is not None


def test_a_server_that_left_leaves_every_view():
    views = ViewRankings(3.0)
    views.take(1, 0.0, ranking([2, 1], [0.001, 0.002]))
    views.take(2, 0.0, ranking([1], [0.001], [2]))
    views.take(3, 0.0, ranking([1], [0.001]))
    assert views.forget_server(2) == [1, 2]
    assert views.rank(1, 0.1).ranking == [1] and views.rank(2, 0.1).excluded == []


def test_the_manager_counts_a_change_of_the_servers_a_robot_ranks_or_leaves_out():
    """What its statuses on /diagnostics publish at once: not a view renewed, nor a new
    order of the same servers."""
    views = ViewRankings(3.0)
    views.take(1, 0.0, ranking([2, 1], [0.001, 0.002]))
    assert views.changes == 1
    views.take(1, 1.0, ranking([1, 2], [0.001, 0.002]))        # reordered
    views.take(1, 2.0, ranking([1, 2], [0.001, 0.002]))        # renewed
    assert views.changes == 1
    views.take(1, 2.5, ranking([1], [0.001], [2]))             # server 2 left out
    assert views.changes == 2
    views.forget_server(3)                                     # in no view
    assert views.changes == 2
    views.forget_server(2)
    assert views.changes == 3


def test_a_robots_view_is_the_ranking_the_manager_made_from_its_samples():
    """What the robot sends equals what the manager ranked from the same samples."""
    clock = [0.0]
    policy = Policy('hysteresis', margin=0.0003)
    selection = Selection(1, [1, 2, 3], 'select', policy=policy, window=1.5, clock=lambda:
                          clock[0], passive=True, task_memory=5.0, keep=3, horizon=8.0,
                          fail_fast=2)
    manager = SampleRankings(1.5, statistic=policy.statistic(), fail_fast=2,
                             robust=policy.robust, task_memory=5.0, keep=3, horizon=8.0)
    compared = 0
    for step in range(80):
        t = clock[0] = step * 0.1
        for server in (1, 2, 3):      # server 3 fails for a while; every 7th is a task
            ok, probe = not (server == 3 and 30 < step < 40), step % 7 != 0
            rtt = 0.001 * server + 0.0001 * math.sin(step)
            selection.on_sample(server, ok, rtt, probe=probe)
            manager.add(1, server, t, ok, rtt, probe=probe)
        if step % 5 == 0:
            assert selection.view() == manager.rank(1, t), step
            compared += 1
    assert compared == 16
    assert selection.view() == rank_servers(manager.window.robot_stats(
        1, manager.servers(1, clock[0]), clock[0]), 2)
