"""Ranking of a robot's servers by latency, as in the paper (mean, stable sort)."""

import collections

from server_select.core.outcome import NO_SERVER  # noqa: F401 (re-exported)

Ranking = collections.namedtuple('Ranking',
                                 'selected ranking means counts excluded errors waits')
Ranking.__new__.__defaults__ = (None, None)
Ranking.__doc__ = """A robot's servers, best first: ``means`` holds each ranked server's
latency statistic (the window mean in the paper; what ``SelectionFlag.mean_latency``
carries), ``errors`` the standard errors of their means (None: not known), ``waits`` the
part of each statistic that is the server's wait (None: a server's, or all, not
load-aware)."""


def latency(stats):
    """The statistic a pair is ranked by: its ``value``, else (no statistic) its mean."""
    return stats.value if stats.value is not None else stats.mean


def rank_servers(pair_stats, fail_fast=0):
    """Rank servers by latency statistic, lowest first.

    ``pair_stats`` maps server id to :class:`server_select.core.window.PairStats`. Servers
    with no successful sample in the window are excluded, and with ``fail_fast`` > 0 those
    whose ``fail_fast`` newest samples failed (a server that stopped answering is left
    then, not when its last good sample leaves the window). The candidates are put in
    ascending id order and then sorted by their statistic with Python's ``sorted``
    (Timsort, which is stable), so equal values rank the lower server id first.
    """
    def ranked(s):
        stats = pair_stats[s]
        return stats.mean is not None and not (fail_fast and stats.failed_run >= fail_fast)
    candidates = [s for s in sorted(pair_stats) if ranked(s)]
    excluded = [s for s in sorted(pair_stats) if not ranked(s)]
    ranking = sorted(candidates, key=lambda s: latency(pair_stats[s]))
    return Ranking(
        selected=ranking[0] if ranking else NO_SERVER,
        ranking=ranking,
        means=[latency(pair_stats[s]) for s in ranking],
        counts=[pair_stats[s].ok_count for s in ranking],
        excluded=excluded,
        errors=[pair_stats[s].se or 0.0 for s in ranking],
        waits=[pair_stats[s].wait for s in ranking],
    )
