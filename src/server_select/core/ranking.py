"""Ranking of a robot's servers by mean latency, as in the paper."""

import collections

from server_select.msg import SelectionFlag

NO_SERVER = SelectionFlag.NO_SERVER

Ranking = collections.namedtuple('Ranking', 'selected ranking means counts excluded')


def rank_servers(pair_stats):
    """Rank servers by mean round trip, lowest first.

    ``pair_stats`` maps server id to :class:`server_select.core.window.PairStats`. Servers
    with no successful sample in the window are excluded. The candidates are put in
    ascending id order and then sorted by mean with Python's ``sorted`` (Timsort, which
    is stable), so equal means rank the lower server id first.
    """
    candidates = [s for s in sorted(pair_stats) if pair_stats[s].mean is not None]
    excluded = [s for s in sorted(pair_stats) if pair_stats[s].mean is None]
    ranking = sorted(candidates, key=lambda s: pair_stats[s].mean)
    return Ranking(
        selected=ranking[0] if ranking else NO_SERVER,
        ranking=ranking,
        means=[pair_stats[s].mean for s in ranking],
        counts=[pair_stats[s].ok_count for s in ranking],
        excluded=excluded,
    )


def choose(ranking, current, hysteresis=0.0):
    """The server to select given the ``current`` one.

    With ``hysteresis`` 0 (the paper) this is the best-ranked server. Otherwise the
    current server is kept while it is still ranked and its mean is within
    ``hysteresis`` seconds of the best, which stops flapping between servers whose means
    differ only by noise.
    """
    if hysteresis > 0 and current in ranking.ranking:
        index = ranking.ranking.index(current)
        if ranking.means[index] - ranking.means[0] <= hysteresis:
            return current
    return ranking.selected
