"""Ranking of a robot's servers by latency, as in the paper (mean, stable sort)."""

import collections

from server_select.core.config.names import NO_SERVER  # noqa: F401 (re-exported)

Ranking = collections.namedtuple('Ranking',
                                 'selected ranking means counts excluded errors waits reason')
Ranking.__new__.__defaults__ = (None, None, '')
Ranking.__doc__ = """A robot's servers, best first: ``means`` holds each ranked server's
latency statistic (the window mean in the paper; what ``SelectionFlag.mean_latency``
carries), ``errors`` the standard errors of their means (None: not known), ``waits`` the
part of each statistic that is the server's wait (None: a server's, or all, not
load-aware), ``reason`` why ``selected`` (a robot's rule's words; empty: the best)."""


def latency(stats):
    """The statistic a pair is ranked by: its ``value``, else (no statistic) its mean."""
    return stats.value if stats.value is not None else stats.mean


def rank_servers(pair_stats, fail_fast=0):
    """Rank servers by latency statistic, lowest first.

    ``pair_stats`` maps server id to :class:`server_select.core.ranking.window.PairStats`. Servers
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


def by_estimate(estimates, selected=None, reason=''):
    """A :class:`Ranking` of ``{server: estimate or None}`` (a rule's own: ``latency``,
    ``error``, ``wait``, ``answers``), ``selected`` where tasks go and ``reason`` why (when
    ranked; else the best); servers with no estimate left out. ``selected`` comes first
    (every view names where tasks go first; when its estimate is not the least, ``reason``
    says why it is kept), the others by estimate."""
    ranked = sorted((s for s, e in estimates.items() if e is not None),
                    key=lambda s: (s != selected, estimates[s].latency, s))
    return Ranking(selected if selected in ranked else ranked[0] if ranked else NO_SERVER,
                   ranked, [estimates[s].latency for s in ranked],
                   [estimates[s].answers for s in ranked],
                   sorted(s for s, e in estimates.items() if e is None),
                   [estimates[s].error for s in ranked], [estimates[s].wait for s in ranked],
                   reason if selected in ranked else '')


def view_key(ranking, policy, current):
    """What of a robot's own ``ranking`` its manager needs to hear at once: the servers
    ranked, those left out, and which server ``policy`` picks from ``current`` (the server
    the robot's flag selects; None: none), which is what the manager decides from. A robot
    sends its ranking when this changes; the order below the pick (on near-equal servers it
    changes with every sample) goes with the periodic ranking."""
    return (frozenset(ranking.ranking), frozenset(ranking.excluded),
            policy.choose(ranking, current))


def from_view(ranking, means, errors, counts, waits, excluded, selected=0, reason=''):
    """A :class:`Ranking` from a robot's message (parallel arrays; ``waits`` may be empty,
    NaN: not known; ``selected``: where a robot that chooses per task sends its tasks, 0:
    the first ranked, first when named, the others ascending; ``reason``: its words for
    why). ValueError says what is wrong with it."""
    ranking = [int(s) for s in ranking]
    if selected and selected not in ranking:
        raise ValueError('it selects server %d, which its ranking %s lacks' % (selected, ranking))
    n = len(ranking)
    if not len(means) == len(errors) == len(counts) == n or len(waits) not in (0, n):
        raise ValueError('arrays of %d servers, %d latencies, %d errors, %d counts, %d waits'
                         % (n, len(means), len(errors), len(counts), len(waits)))
    if len(set(ranking)) < n or set(ranking) & set(excluded):
        raise ValueError('a server is named twice in ranking %s, excluded %s'
                         % (ranking, list(excluded)))
    means = [float(m) for m in means]
    rest = means[1:] if selected and ranking[:1] == [selected] else means
    if not all(0.0 < m < float('inf') for m in means) or \
            any(b < a for a, b in zip(rest, rest[1:])):
        raise ValueError('latencies %s are not positive and ascending' % means)
    errors = [float(e) for e in errors]
    if not all(0.0 <= e < float('inf') for e in errors):
        raise ValueError('standard errors %s are not finite and >= 0' % errors)
    waits = [None if w != w else float(w) for w in waits] if len(waits) else [None] * n
    if not all(w is None or 0.0 <= w < float('inf') for w in waits):
        raise ValueError('waits %s are not finite and >= 0 (or NaN: not known)' % waits)
    return Ranking(selected=selected or (ranking[0] if ranking else NO_SERVER),
                   ranking=ranking, means=means, counts=[int(c) for c in counts],
                   excluded=[int(s) for s in excluded], errors=errors, waits=waits,
                   reason=str(reason) if selected else '')


def only(ranking, wanted):
    """``ranking`` with only the servers for which ``wanted(server)`` is true."""
    keep = [i for i, s in enumerate(ranking.ranking) if wanted(s)]
    first = ranking.ranking[keep[0]] if keep else NO_SERVER
    kept = ranking.selected in ranking.ranking and wanted(ranking.selected)
    return Ranking(selected=ranking.selected if kept else first,
                   reason=ranking.reason if kept else '',
                   ranking=[ranking.ranking[i] for i in keep],
                   means=[ranking.means[i] for i in keep],
                   counts=[ranking.counts[i] for i in keep],
                   excluded=[s for s in ranking.excluded if wanted(s)],
                   errors=[ranking.errors[i] for i in keep] if ranking.errors else None,
                   waits=[ranking.waits[i] for i in keep] if ranking.waits else None)
