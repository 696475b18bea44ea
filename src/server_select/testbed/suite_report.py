"""Tables of the scenario suite, recomputed from its bags (pure functions but ``load_runs``).

Per run and variant: task round trips in the measured part of the run (from the
metadata's ``measure_from`` to the end) with every failed task counted at the task
timeout, their mean and p99 as ratios to the oracle's *of the same run* (with the same
task routing: ``oracle_fleet`` for the fleet profile's variants), the failed count,
switches per minute per robot from the flags, and the reaction to each change of the truly
nearest server (from the change to the first flag selecting it). Across repeated runs:
median and range.
"""

import collections
import glob
import json
import os
import statistics

from server_select.core.util.stats import summarize
from server_select.core.util.tables import fmt, markdown_table, median_range
from server_select.testbed.bag_analysis import felt_changes, oracle_changes, reaction_times
from server_select.testbed.scenario import Scenario
from server_select.testbed.suite import VARIANTS

# the league's keys (core/util/league_columns.py): switches a minute per robot, mean
# reaction (s), probe samples a second per robot, extra sends per task (a fraction)
Figures = collections.namedtuple('Figures', 'tasks failed mean p99 switches reaction '
                                 'reaction_max missed probes robot_cpu extra reaction_felt')
Figures.__new__.__defaults__ = (None, None, None, None)
TARGETS = {      # scenario: what the fleet profile is to reach
    'paper_moving': dict(mean=1.05, p99=1.2, failed=0, reaction=1.5),
    'crossing': dict(mean=1.05, p99=1.2, failed=0, reaction=1.5),
    'near_equal': dict(mean=1.05, switches=2.0),
}


def load_runs(scenario_dir):
    """``[(meta, Run)]`` of every ``run<i>.bag`` in ``scenario_dir``."""
    from server_select.testbed.bag_analysis import load
    runs = [load(bag) for bag in sorted(glob.glob(os.path.join(scenario_dir, 'run*.bag')))]
    return [(run.meta, run) for run in runs]


def split(run, owners):
    """``{variant: (reports, flags, [robot ids], probe samples)}`` of one run."""
    parts = collections.OrderedDict()
    for rid, (variant, _) in sorted(owners.items()):
        parts.setdefault(variant, ([], [], [], []))[2].append(rid)
    where = dict((rid, variant) for rid, (variant, _) in owners.items())
    for report in run.reports:
        if report.robot in where:
            parts[where[report.robot]][0].append(report)
    for flag in run.flags:
        if flag.robot in where:
            parts[where[flag.robot]][1].append(flag)
    for sample in run.samples:
        if sample.robot in where:
            parts[where[sample.robot]][3].append(sample)
    return parts


def flag_switches(flags, start, end):
    """Changes of the selected server in ``flags`` between ``start`` and ``end``, all
    robots together (a robot's first flag is no change)."""
    last, count = {}, 0
    for flag in sorted(flags, key=lambda f: f.t):
        if flag.t < start or flag.t > end:
            last[flag.robot] = flag.server
            continue
        if flag.robot in last and last[flag.robot] != flag.server:
            count += 1
        last[flag.robot] = flag.server
    return count


def _reactions(flags, changes, robots, start, end):
    """``(reached, missed)``: the reactions (s) of ``robots`` to the ``changes`` between
    ``start`` and ``end``, and how many were not reached (none without flags)."""
    mine = [c for c in changes if c[1] in robots and start <= c[0] <= end]
    reactions = [r[3] for r in reaction_times(flags, mine)] if flags else []
    reached = [r for r in reactions if r is not None]
    return reached, len(reactions) - len(reached)


def _mean(values):
    return sum(values) / len(values) if values else None


def figures(reports, flags, robots, changes, start, end, timeout, samples=(), cpu=None,
            felt=()):
    """:class:`Figures` of one variant in one run (``cpu``: its robots' mean CPU share,
    %; ``felt``: the changes from when a task would feel them, for ``reaction_felt``)."""
    measured = [r for r in reports if start <= r.t <= end]
    rtt = summarize([r.rtt if r.ok else timeout for r in measured])
    minutes = max(1e-9, (end - start) / 60.0)
    reached, missed = _reactions(flags, changes, robots, start, end)
    return Figures(len(measured), sum(1 for r in measured if not r.ok), rtt.get('mean'),
                   rtt.get('p99'), flag_switches(flags, start, end) / minutes / len(robots),
                   _mean(reached), max(reached) if reached else None, missed,
                   sum(1 for x in samples if start <= x.t <= end)
                   / max(1e-9, end - start) / len(robots),
                   cpu, sum(max(0, r.attempts - 1) for r in measured) / max(1, len(measured)),
                   _mean(_reactions(flags, felt, robots, start, end)[0]) if flags else None)


def run_figures(meta, run, by_tasks=False):
    """``{variant: Figures}`` of one run; ``by_tasks``: switches and reactions from where
    tasks went (the server each was first sent to), not from the flags (what the league
    compares: a peer's robots choose per task, and flags do not say what they did)."""
    owners = dict((int(k), tuple(v)) for k, v in meta['owners'].items())
    scenario = Scenario.load(meta['scenario'])
    start, end = meta['measure_from'], meta['duration']
    changes = oracle_changes(scenario, sorted(owners), start, end)
    felt = felt_changes(scenario, changes)
    timeout, cpu = meta['options']['task_timeout'], meta.get('robot_cpu', {})

    def share(robots):
        known = [cpu[str(r)] for r in robots if str(r) in cpu]
        return sum(known) / len(known) if known else None
    return collections.OrderedDict(
        (variant, figures(reports, reports if by_tasks else flags, robots, changes, start,
                          end, timeout, samples, share(robots), felt))
        for variant, (reports, flags, robots, samples) in split(run, owners).items())


def reference(variant, variants):
    """The oracle ``variant`` is compared with: the one with the same task routing (the
    fleet profile's direct routing, or the paper's broadcast) and, where the run has one,
    on the same kind of robot hosts (a Pi robot's round trips include its own slowness)."""
    spec = VARIANTS.get(variant)
    profile, host = (spec.profile, spec.host) if spec is not None else ('paper', {})
    oracles = [v for v in variants if v in VARIANTS and VARIANTS[v].mode == 'oracle']
    for want in (host, {}):
        for oracle in oracles:
            if VARIANTS[oracle].profile == profile and VARIANTS[oracle].host == want:
                return oracle
    return 'oracle'


def ratios(per_run):
    """``[{variant: (mean ratio, p99 ratio)}]`` to the oracle of the same run and routing."""
    out = []
    for variants in per_run:
        row = {}
        for v, f in variants.items():
            oracle = variants.get(reference(v, variants))
            row[v] = (f.mean / oracle.mean if oracle and oracle.mean and f.mean else None,
                      f.p99 / oracle.p99 if oracle and oracle.p99 and f.p99 else None)
        out.append(row)
    return out


def _cell(values, spec):
    values = [v for v in values if v is not None]
    return median_range(values, spec) if values else '-'


def scenario_rows(per_run):
    """One table row per variant: median (range) over the runs."""
    rel = ratios(per_run)
    rows = []
    for variant in per_run[0]:
        runs = [r[variant] for r in per_run if variant in r]
        ratio = [r[variant] for r in rel if variant in r]
        rows.append([variant, len(runs), _cell([f.tasks for f in runs], '%d'),
                     _cell([f.failed for f in runs], '%d'),
                     _cell([f.mean * 1e3 for f in runs if f.mean], '%.2f'),
                     _cell([x[0] for x in ratio], '%.3f'),
                     _cell([f.p99 * 1e3 for f in runs if f.p99], '%.1f'),
                     _cell([x[1] for x in ratio], '%.2f'),
                     _cell([f.switches for f in runs], '%.2f'),
                     _cell([f.reaction for f in runs], '%.2f'),
                     _cell([f.reaction_max for f in runs], '%.2f'),
                     _cell([f.missed for f in runs], '%d'),
                     _cell([f.probes for f in runs], '%.1f'),
                     _cell([f.robot_cpu for f in runs], '%.1f'),
                     _cell([100.0 * f.extra for f in runs if f.extra is not None], '%.1f')])
    return rows


HEADER = ('variant', 'runs', 'tasks', 'failed', 'mean ms', 'mean / oracle', 'p99 ms',
          'p99 / oracle', 'switches /min /robot', 'reaction mean s', 'reaction max s',
          'changes not reached', 'probes /s /robot', 'robot CPU %',
          'extra sends % (hedged, re-sent)')


def scenario_table(per_run):
    return markdown_table(HEADER, scenario_rows(per_run))


def summary_table(results):
    """One row per variant, one column per scenario: ``mean x / p99 x / failed``
    (medians over the runs)."""
    scenarios = list(results)
    variants = []
    for per_run in results.values():
        variants += [v for v in per_run[0] if v not in variants]
    rows = []
    for variant in variants:
        row = [variant]
        for name in scenarios:
            per_run = results[name]
            rel = [r[variant] for r in ratios(per_run) if variant in r]
            failed = [r[variant].failed for r in per_run if variant in r]
            row.append('%s / %s / %s' % (fmt(_median([x[0] for x in rel])),
                                         fmt(_median([x[1] for x in rel])),
                                         fmt(_median(failed), '%d')))
        rows.append(row)
    return markdown_table(['variant'] + scenarios, rows)


def targets_table(results, variant='fleet'):
    """The fleet profile against the targets: measured (median of runs) and met or not."""
    rows = []
    for name, target in TARGETS.items():
        if name not in results:
            continue
        per_run, rel = results[name], ratios(results[name])
        runs = [r[variant] for r in per_run if variant in r]
        measured = {
            'mean': _median([r[variant][0] for r in rel if variant in r]),
            'p99': _median([r[variant][1] for r in rel if variant in r]),
            'failed': _median([f.failed for f in runs]),
            'reaction': _median([f.reaction for f in runs]),
            'switches': _median([f.switches for f in runs]),
        }
        for key, goal in target.items():
            value = measured[key]
            met = value is not None and value <= goal
            rows.append([name, key, '<= %g' % goal, fmt(value, '%.3f'),
                         'yes' if met else 'no (by %s)' % fmt(
                             None if value is None else value - goal, '%+.3f')])
    return markdown_table(('scenario', 'figure', 'target', variant + ' (median of runs)',
                           'met'), rows)


def _median(values):
    """The median of the known ``values`` (None: none known)."""
    known = [v for v in values if v is not None]
    return statistics.median(known) if known else None


def write_json(results, path):
    with open(path, 'w') as stream:
        json.dump(dict((name, [dict((v, f._asdict()) for v, f in r.items()) for r in per_run])
                       for name, per_run in results.items()), stream, indent=1)
