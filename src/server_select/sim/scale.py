"""Scale cells of the simulator (``python3 -m server_select.sim.scale``): many robots and
servers, each robot's links drawn at random (1-20 ms one way), sort tasks at 2 a second;
with ``--group`` G, servers form groups of G and each robot probes and uses its group's
only (a grouped fleet). Prints the simulator's wall and CPU time, and the rule's own CPU
per decision (where a task goes: ``Selection.candidates``, timed around every call).

A grouped fleet's groups share nothing (no robot probes or sends outside its group, every
random draw comes from a stream of its own: :mod:`~server_select.sim.events`), so its
groups run as simulations of their own, side by side on the simulator's engine
(:mod:`~server_select.sim.cells`), and their figures add up to the whole run's (``--whole``
runs it as one, to check).
"""

import argparse
import json
import random
import sys
import time

from server_select.core.robot.selection import Selection
from server_select.sim import cells
from server_select.sim.figures import figures
from server_select.sim.model import Model
from server_select.sim.run import simulate
from server_select.testbed.scenario import Scenario


def field(robots, servers, duration, seed=1, only=None):
    """The cell's scenario; ``only``: ``(robot ids, server ids)`` of it, with the links
    they have in the whole one."""
    rng = random.Random('scale/%d' % seed)
    delays = dict(((r, s), round(rng.uniform(1, 20), 2))
                  for r in range(1, robots + 1) for s in range(1, servers + 1))
    robot_ids, server_ids = only or (range(1, robots + 1), range(1, servers + 1))
    hosts = {'manager': {'role': 'manager'}}
    hosts.update(('server%d' % s, {'role': 'server', 'id': s}) for s in server_ids)
    hosts.update(('robot%d' % r, {'role': 'robot', 'id': r}) for r in robot_ids)
    links = dict(('robot%d server%d' % (r, s), [{'at': 0, 'delay': delays[(r, s)],
                                                 'jitter': 0.3}])
                 for r in robot_ids for s in server_ids)
    return Scenario({'name': 'scale', 'duration': duration, 'hosts': hosts, 'links': links,
                     'suite': {'measure_from': 10.0}}, 'scale')


def groups_of(robots, servers, group):
    """``[(robot ids, server ids)]`` of each group (robots dealt to groups in turn)."""
    count = servers // group
    return [([r for r in range(1, robots + 1) if (r - 1) % count == g],
             list(range(g * group + 1, (g + 1) * group + 1))) for g in range(count)]


class _Timed(object):
    """Times every ``Selection.candidates`` call while in effect."""

    def __init__(self):
        self.calls, self.seconds = 0, 0.0

    def __enter__(self):
        self.original = original = Selection.candidates

        def timed(selection, kind=None, fresh=None):
            start = time.perf_counter()
            try:
                return original(selection, kind, fresh)
            finally:
                self.seconds += time.perf_counter() - start
                self.calls += 1
        Selection.candidates = timed
        return self

    def __exit__(self, *exc):
        Selection.candidates = self.original


def _run(job):
    """The sums of one simulation of the cell (the whole, or one group: ``only``)."""
    robots, servers, group, duration, variant, seed, only = job
    scenario = field(robots, servers, duration, seed, only)
    groups = dict((r, s) for ids, s in groups_of(robots, servers, group) for r in ids
                  if only is None or r in only[0]) if group else None
    cpu = time.process_time()
    with _Timed() as timed:
        sim = simulate(scenario, Model.load(), seed, [variant], groups=groups)
    row, count = figures(sim, variant), len(scenario.of_role('robot'))
    return {'cpu_s': time.process_time() - cpu, 'events': sim.loop.events, 'tasks': row.tasks,
            'ms': 1e3 * row.mean * row.tasks if row.tasks else 0.0, 'failed': row.failed,
            'probes': row.probes * duration * count, 'robots': count,
            'decisions': timed.calls, 'decision_s': timed.seconds}


def cell(robots, servers, group, duration, variant, seed=1, whole=False, scheduler=None,
         processes=None):
    """One cell's row: a grouped one as its groups side by side (``whole``: as one)."""
    parts = [None] if whole or not group else groups_of(robots, servers, group)
    jobs = [(robots, servers, group, duration, variant, seed, part) for part in parts]
    wall = time.monotonic()
    sums = list(cells.run(_run, jobs, scheduler, processes, log=lambda _line: None)) \
        if len(jobs) > 1 else [_run(jobs[0])]
    total = dict((key, sum(s[key] for s in sums)) for key in sums[0])
    return {'robots': robots, 'servers': servers, 'group': group, 'variant': variant,
            'simulated_s': duration, 'wall_s': time.monotonic() - wall,
            'cpu_s': total['cpu_s'], 'events': total['events'], 'tasks': total['tasks'],
            'mean_ms': total['ms'] / max(1, total['tasks']), 'failed': total['failed'],
            'probes_per_s_per_robot': total['probes'] / duration / total['robots'],
            'decisions': total['decisions'], 'parts': len(jobs),
            'us_per_decision': 1e6 * total['decision_s'] / max(1, total['decisions'])}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--cells', default='100x20,1000x100/10',
                        help='ROBOTSxSERVERS[/GROUP], comma-separated (%(default)s)')
    parser.add_argument('--seconds', type=float, default=120.0, help='simulated s')
    parser.add_argument('--variants', default='fleet,prequal')
    parser.add_argument('--whole', action='store_true', help='a grouped cell as one '
                        'simulation, not its groups side by side')
    cells.add_arguments(parser)
    parser.add_argument('--out', help='also write the rows as JSON here')
    args = parser.parse_args(argv)
    rows = []
    for spec in args.cells.split(','):
        size, _, group = spec.partition('/')
        robots, servers = (int(x) for x in size.split('x'))
        for variant in args.variants.split(','):
            row = cell(robots, servers, int(group) if group else 0, args.seconds, variant,
                       whole=args.whole, scheduler=args.scheduler, processes=args.processes)
            rows.append(row)
            print('%dx%d%s %s: %.0f s wall (%.0f CPU s, %d simulations) for %.0f simulated s, '
                  '%d events, %d tasks, mean %.1f ms, %d failed, %.1f probes/s/robot; the rule '
                  '%.0f us a decision (%d)' % (
                      robots, servers, ' grouped by %s' % group if group else '', variant,
                      row['wall_s'], row['cpu_s'], row['parts'], args.seconds, row['events'],
                      row['tasks'],
                      row['mean_ms'], row['failed'], row['probes_per_s_per_robot'],
                      row['us_per_decision'], row['decisions']), flush=True)
    if args.out:
        with open(args.out, 'w') as stream:
            json.dump(rows, stream, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
