"""What a fleet key costs the nodes (``make bench-seal``): CPU and memory per role with and
without a key, side by side.

Each run starts two fleets side by side, each under a roscore of its own
(``demo.launch profile:=fleet``: ``--servers`` servers, one robot sending sort tasks at
``--task-rate``, the manager): one with a fleet key on every node, one without. After
``--warmup`` s, the CPU (% of one core) and resident memory of each fleet's robot, manager
and servers over ``--seconds`` s. ``--repeats`` runs (the keyed fleet on the other port each
time); printed: median (min-max) per role with and without the key, and the keyed robot's
CPU over the unkeyed one's, per run. Nothing is asserted.
"""

import contextlib
import os
import statistics
import sys
import tempfile
import time

from server_select.bench import cli
from server_select.bench.harness import Roscore, launched
from server_select.core.trust.keys import make_key
from server_select.core.util.procs import measure
from server_select.core.util.tables import markdown_table

ROLES = ('robot', 'manager', 'server')


def one_run(options, key, work, repeat):
    """``{keyed: {role: [usage of each node]}}`` of one run of the two fleets."""
    nodes = ['/manager', '/robot1'] + ['/server%d' % s for s in range(1, options.servers + 1)]
    fleet_args = ['output:=log', 'profile:=fleet', 'n_robots:=1',
                  'n_servers:=%d' % options.servers, 'task_rate:=%g' % options.task_rate]
    with Roscore(work) as first, Roscore(work) as second, contextlib.ExitStack() as fleets:
        masters = (first.uri, second.uri) if repeat % 2 else (second.uri, first.uri)
        pids = [fleets.enter_context(launched(
            'demo.launch', fleet_args + (['fleet_key:=%s' % key] if keyed else []),
            os.path.join(work, 'run%d_%s.log' % (repeat, 'key' if keyed else 'nokey')),
            master, nodes)) for keyed, master in zip((True, False), masters)]
        time.sleep(options.warmup)           # tasks flow, windows fill
        usage = measure([p for each in pids for p in each.values()], options.seconds)
    result = {}
    for keyed, each in zip((True, False), pids):
        result[keyed] = dict((role, [usage[p] for node, p in each.items()
                                     if p in usage and node.strip('/').rstrip('0123456789')
                                     == role]) for role in ROLES)
    return result


def _cell(values):
    return '%.2f (%.2f-%.2f)' % (statistics.median(values), min(values), max(values)) \
        if values else '-'


def table(runs):
    """Median (min-max) over the runs of each role's CPU and RSS, with and without a key."""
    rows = []
    for role in ROLES:
        for keyed in (True, False):
            cpu = [statistics.mean(u['cpu_percent'] for u in run[keyed][role])
                   for run in runs if run[keyed][role]]
            rss = [statistics.mean(u['rss_mb'] for u in run[keyed][role])
                   for run in runs if run[keyed][role]]
            rows.append([role, 'on' if keyed else 'off', _cell(cpu), _cell(rss)])
    ratios = [statistics.mean(u['cpu_percent'] for u in run[True]['robot']) /
              statistics.mean(u['cpu_percent'] for u in run[False]['robot'])
              for run in runs if run[True]['robot'] and run[False]['robot']]
    return markdown_table(['node', 'key', 'CPU % of a core', 'RSS MiB'], rows), ratios


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--servers', type=int, default=4)
    parser.add_argument('--task-rate', type=float, default=2.0, help='sort tasks per s')
    parser.add_argument('--warmup', type=float, default=20.0)
    parser.add_argument('--seconds', type=float, default=60.0)
    parser.add_argument('--repeats', type=int, default=3)
    options = parser.parse_args(argv)
    work = tempfile.mkdtemp(prefix='seal_fleet_')
    key = os.path.join(work, 'fleet.key')
    make_key(key)
    runs = []
    for repeat in range(1, options.repeats + 1):
        runs.append(one_run(options, key, work, repeat))
        print('run %d of %d done' % (repeat, options.repeats), file=sys.stderr, flush=True)
    text, ratios = table(runs)
    text += '\nrobot CPU with the key / without, per run: %s (median %.3f)\n' % (
        ', '.join('%.3f' % r for r in ratios), statistics.median(ratios) if ratios else 0)
    cli.write(options.out, 'seal_fleet.json', [dict((('key' if k else 'nokey'), v)
                                                    for k, v in run.items()) for run in runs])
    cli.write(options.out, 'seal_fleet.md', text)
    print('a fleet key\'s cost: 1 robot, %d servers, sort tasks at %g/s, %d runs of %g s '
          '(logs in %s):\n%s' % (options.servers, options.task_rate, options.repeats,
                                 options.seconds, work, text))
    return 0


if __name__ == '__main__':
    sys.exit(main())
