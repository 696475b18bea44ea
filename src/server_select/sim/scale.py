"""Scale cells of the simulator (``python3 -m server_select.sim.scale``): many robots and
servers, each robot's links drawn at random (1-20 ms one way), sort tasks at 2 a second;
with ``--group`` G, servers form groups of G and each robot probes and uses its group's
only (a grouped fleet). Prints the simulator's wall and CPU time, and the rule's own CPU
per decision (where a task goes: ``Selection.candidates``, timed around every call).
"""

import argparse
import json
import random
import sys
import time

from server_select.core.robot.selection import Selection
from server_select.sim.figures import figures
from server_select.sim.model import Model
from server_select.sim.run import simulate
from server_select.testbed.scenario import Scenario


def field(robots, servers, duration, seed=1):
    rng = random.Random('scale/%d' % seed)
    hosts = {'manager': {'role': 'manager'}}
    hosts.update(('server%d' % s, {'role': 'server', 'id': s}) for s in range(1, servers + 1))
    hosts.update(('robot%d' % r, {'role': 'robot', 'id': r}) for r in range(1, robots + 1))
    links = dict(('robot%d server%d' % (r, s), [{'at': 0, 'delay': round(rng.uniform(1, 20), 2),
                                                 'jitter': 0.3}])
                 for r in range(1, robots + 1) for s in range(1, servers + 1))
    return Scenario({'name': 'scale', 'duration': duration, 'hosts': hosts, 'links': links,
                     'suite': {'measure_from': 10.0}}, 'scale')


class _Timed(object):
    """Times every ``Selection.candidates`` call while in effect."""

    def __init__(self):
        self.calls, self.seconds = 0, 0.0

    def __enter__(self):
        self.original = original = Selection.candidates

        def timed(selection, kind=None):
            start = time.perf_counter()
            try:
                return original(selection, kind)
            finally:
                self.seconds += time.perf_counter() - start
                self.calls += 1
        Selection.candidates = timed
        return self

    def __exit__(self, *exc):
        Selection.candidates = self.original


def cell(robots, servers, group, duration, variant, seed=1):
    scenario = field(robots, servers, duration, seed)
    groups = dict((r, [s for s in range(1, servers + 1)
                       if (s - 1) // group == (r - 1) % (servers // group)])
                  for r in range(1, robots + 1)) if group else None
    wall, cpu = time.monotonic(), time.process_time()
    with _Timed() as timed:
        sim = simulate(scenario, Model.load(), seed, [variant], groups=groups)
    row = figures(sim, variant)
    return {'robots': robots, 'servers': servers, 'group': group, 'variant': variant,
            'simulated_s': duration, 'wall_s': time.monotonic() - wall,
            'cpu_s': time.process_time() - cpu, 'events': sim.loop.events,
            'tasks': row.tasks, 'mean_ms': 1e3 * row.mean, 'failed': row.failed,
            'probes_per_s_per_robot': row.probes, 'decisions': timed.calls,
            'us_per_decision': 1e6 * timed.seconds / max(1, timed.calls)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--cells', default='100x20,1000x100/10',
                        help='ROBOTSxSERVERS[/GROUP], comma-separated (%(default)s)')
    parser.add_argument('--seconds', type=float, default=120.0, help='simulated s')
    parser.add_argument('--variants', default='fleet,prequal')
    parser.add_argument('--out', help='also write the rows as JSON here')
    args = parser.parse_args(argv)
    rows = []
    for spec in args.cells.split(','):
        size, _, group = spec.partition('/')
        robots, servers = (int(x) for x in size.split('x'))
        for variant in args.variants.split(','):
            row = cell(robots, servers, int(group) if group else 0, args.seconds, variant)
            rows.append(row)
            print('%dx%d%s %s: %.0f s wall (%.0f CPU s) for %.0f simulated s, %d events, '
                  '%d tasks, mean %.1f ms, %d failed, %.1f probes/s/robot; the rule %.0f us '
                  'a decision (%d)' % (
                      robots, servers, ' grouped by %s' % group if group else '', variant,
                      row['wall_s'], row['cpu_s'], args.seconds, row['events'], row['tasks'],
                      row['mean_ms'], row['failed'], row['probes_per_s_per_robot'],
                      row['us_per_decision'], row['decisions']), flush=True)
    if args.out:
        with open(args.out, 'w') as stream:
            json.dump(rows, stream, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
