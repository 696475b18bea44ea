"""What a bag analysis says (:mod:`server_select.testbed.bag_analysis` computes it, no
rospy): the table of its summaries, a legend of the columns, the comparison with the
fixed server and the oracle, and a one-line verdict."""

from server_select.core.util.tables import fmt, markdown_table


def compare(summaries):
    """Add improvement vs ``fixed`` and gap to ``oracle`` (by mean round trip, %)."""
    def mean(mode):
        return summaries.get(mode, {}).get('rtt_ms', {}).get('mean')
    for mode, s in summaries.items():
        m = s.get('rtt_ms', {}).get('mean')
        s['vs_fixed_pct'] = (100.0 * (mean('fixed') - m) / mean('fixed')
                             if m is not None and mean('fixed') else None)
        s['gap_to_oracle_pct'] = (100.0 * (m - mean('oracle')) / mean('oracle')
                                  if m is not None and mean('oracle') else None)
    return summaries


def _applies(summaries):
    """Which optional columns have a figure in some row: vs fixed (a fixed run), gap to
    oracle (an oracle run), reaction (a scenario); and whether the rows are modes."""
    rows = summaries.values()
    return {'mode': bool(set(summaries) & {'select', 'fixed', 'oracle', 'fleet'}),
            'vs fixed': any(s.get('vs_fixed_pct') is not None for s in rows),
            'gap to oracle': any(s.get('gap_to_oracle_pct') is not None for s in rows),
            'reaction': any(s.get('reactions') for s in rows)}


def table(summaries, first='mode'):
    """Markdown table of :func:`mode_summary` results, one row per mode (or bag: the
    first column's heading is ``first``); the columns that apply to no row are left out
    (:func:`legend` says which and why)."""
    applies = _applies(summaries)
    rows = []
    for mode, s in summaries.items():
        r = s['rtt_ms']
        reaction = '-'
        if s.get('reactions'):
            reaction = '%s / %s (%d)' % (fmt(s['reaction_mean_s']), fmt(s['reaction_max_s']),
                                         s['reaction_missed'])
        rows.append([mode, s['tasks'], s['failed']]
                    + [fmt(r.get(k)) for k in ('mean', 'median', 'p95', 'p99', 'max')]
                    + [fmt(s.get('vs_fixed_pct'), '%+.1f %%')] * applies['vs fixed']
                    + [fmt(s.get('gap_to_oracle_pct'), '%+.1f %%')] * applies['gap to oracle']
                    + [s['switches']] + [reaction] * applies['reaction'])
    header = [first, 'tasks', 'failed', 'mean ms', 'median ms', 'p95 ms', 'p99 ms', 'max ms'] \
        + ['vs fixed'] * applies['vs fixed'] + ['gap to oracle'] * applies['gap to oracle'] \
        + ['switches'] + ['reaction mean / max s (missed)'] * applies['reaction']
    return markdown_table(header, rows)


LEGEND = (
    ('mode', "select: the paper's system; fixed: one server for all (the paper's baseline); "
     'oracle: the truly nearest server; fleet: the system in the fleet profile'),
    ('tasks, failed', "the robots' task reports, and those that got no right answer in time"),
    ('mean ... max ms', 'task round trip, each failed task counted at the task timeout'),
    ('vs fixed', "how much lower the mean is than the fixed server's (+: faster)"),
    ('gap to oracle', "how much higher the mean is than that of the oracle, which follows "
     'the truly nearest server of the scenario (+: slower)'),
    ('switches', 'changes of the server a robot sent its tasks to'),
    ('reaction', 'seconds from a change of the truly nearest server to the flag selecting it, '
     'mean / max (changes never followed)'),
)
WHY_LEFT_OUT = {'vs fixed': 'no fixed run to compare with',
                'gap to oracle': 'no oracle run to compare with',
                'reaction': 'no scenario, which says when the nearest server changes'}


def legend(summaries):
    """What the columns of :func:`table` mean, one line each, and which columns were left
    out, and why."""
    applies = _applies(summaries)
    lines = ['%s: %s' % (name, text) for name, text in LEGEND if applies.get(name, True)]
    left_out = [name for name in WHY_LEFT_OUT if not applies[name]]
    if left_out:
        lines.append('(left out: %s)' % '; '.join(
            '%s, %s' % (name, WHY_LEFT_OUT[name]) for name in left_out))
    return '\n'.join(lines)


def verdicts(summaries):
    """The lines that end an evaluation: a verdict for each profile's run, and the two
    profiles compared when both ran."""
    lines = ['verdict: %s' % verdict(summaries, mode) for mode in
             [m for m in ('select', 'fleet') if m in summaries] or ['select']]
    if 'select' in summaries and 'fleet' in summaries:
        lines.append('profiles: %s' % profiles(summaries))
    return lines


def profiles(summaries):
    """One line comparing the fleet profile's run (``fleet``) with the paper's (``select``)
    on the same scenario, by mean task round trip and failed tasks."""
    paper, fleet = summaries['select'], summaries['fleet']
    a, b = paper['rtt_ms']['mean'], fleet['rtt_ms']['mean']
    change = 100.0 * (a - b) / a if a else 0.0
    return ('the fleet profile was %.0f %% %s than the paper\'s on this scenario (%.1f ms '
            'against %.1f ms), %d against %d tasks failed; the paper profile reproduces the '
            'papers, the fleet profile is for work that must live through faults and '
            'overload.' % (abs(change), 'faster' if change >= 0 else 'slower', b, a,
                           fleet['failed'], paper['failed']))


def verdict(summaries, mode='select'):
    """One line of what ``mode`` achieved against the fixed server and the oracle (by mean
    task round trip, failed tasks counted at the timeout), and how many tasks failed."""
    s = summaries.get(mode)
    if s is None:
        return 'no %s run to judge' % mode
    parts = []
    if s.get('vs_fixed_pct') is not None:
        parts.append('%.0f %% %s than a fixed server' % (
            abs(s['vs_fixed_pct']), 'faster' if s['vs_fixed_pct'] >= 0 else 'slower'))
    if s.get('gap_to_oracle_pct') is not None:
        parts.append('%.0f %% %s than the oracle that knows the network' % (
            abs(s['gap_to_oracle_pct']), 'slower' if s['gap_to_oracle_pct'] >= 0 else 'faster'))
    judged = ('%s was %s (mean task round trip); ' % (mode, ' and '.join(parts))) if parts \
        else '%s: nothing to compare with; ' % mode
    return judged + '%d of %d tasks failed.' % (s['failed'], s['tasks'])
