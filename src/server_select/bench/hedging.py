"""Hedged tasks on lossy links (testbed, root): tail round trip vs extra requests.

Two robots send sort tasks at ``--rate`` each to two servers over links of ``--delay`` ms
one way with ``--loss`` packet loss (a lost packet costs a TCP retransmission, 200 ms or
more: the tail "The Tail at Scale" hedges against), the manager selecting: robot 1 with
``hedge:=false``, robot 2 with ``hedge:=true`` (a copy to the next server once a task is
past its server's p95 round trip by a median one), side by side on links alike,
``--runs`` times. Printed per setting: tasks, failed (counted at the task timeout), round
trip p50 / p99 / p99.9 / max, the share of tasks answered by a second server, and the
extra requests per task (every attempt after the first: hedges and re-sends). Median of
the runs, (min-max).
"""

import sys
import tempfile

import numpy as np

from server_select.bench import cli
from server_select.bench.harness import scenario_run
from server_select.core.util.tables import markdown_table, median_range
from server_select.testbed import bag_analysis

TIMEOUT = 2.0


ROBOTS = {'off': 1, 'on': 2}       # the setting each robot runs with


def scenario(delay, loss, seconds):
    links = {}
    for robot in ROBOTS.values():
        links['robot%d server1' % robot] = [{'at': 0, 'delay': delay, 'loss': loss}]
        links['robot%d server2' % robot] = [{'at': 0, 'delay': delay * 1.5, 'loss': loss}]
    hosts = {'manager': {'role': 'manager'}, 'server1': {'role': 'server', 'id': 1},
             'server2': {'role': 'server', 'id': 2}}
    hosts.update(('robot%d' % r, {'role': 'robot', 'id': r}) for r in ROBOTS.values())
    # time from the nodes' registration: the first tasks 3 s later, the manager's window
    # full 5 s later
    return {'name': 'hedging', 'duration': seconds + 7, 'time_zero': 'ready',
            'hosts': hosts, 'default': {'delay': 0.5}, 'links': links}


def figures(reports):
    rtts = np.array([r.rtt if r.ok else TIMEOUT for r in reports])
    attempts = [max(1, r.attempts) for r in reports]
    p50, p99, p999 = np.percentile(rtts, [50, 99, 99.9]) if len(rtts) else (0, 0, 0)
    return {'tasks': len(reports), 'failed': sum(1 for r in reports if not r.ok),
            'p50': p50, 'p99': p99, 'p999': p999, 'max': float(rtts.max()) if len(rtts) else 0,
            'second': sum(1 for r in reports if r.ok and r.answered_by != r.server) /
            max(1, len(reports)), 'extra': (sum(attempts) - len(attempts)) / max(1, len(reports))}


def run_once(args, work, index):
    """One run, both settings side by side: ``{setting: figures}``."""
    data = scenario(args.delay, args.loss, args.seconds)
    with scenario_run(data, work, 'hedging-%d' % index, 'sshd') as (run, bag):
        run.launch('manager', 'manager.launch', 'robots:=1,2', 'servers:=1,2')
        for server in (1, 2):
            run.launch('server%d' % server, 'server.launch', 'server_id:=%d' % server)
        for setting, robot in ROBOTS.items():
            run.launch('robot%d' % robot, 'robot.launch', 'robot_id:=%d' % robot,
                       'servers:=1,2', 'task_rate:=%g' % args.rate,
                       'task_timeout:=%g' % TIMEOUT, 'start_delay:=3',
                       'hedge:=%s' % ('true' if setting == 'on' else 'false'), stage=0)
    start = data['duration'] - args.seconds            # the last --seconds of the run
    reports = [r for r in bag_analysis.load(bag).reports if r.t > start]
    return dict((setting, figures([r for r in reports if r.robot == robot]))
                for setting, robot in ROBOTS.items())


def table(results):
    def spread(runs, key, fmt, scale=1.0):
        return median_range([scale * r[key] for r in runs], fmt)
    return markdown_table(
        ('hedge', 'tasks', 'failed', 'p50 ms', 'p99 ms', 'p99.9 ms', 'max ms',
         'answered by a 2nd server %', 'extra requests per task %'),
        [(setting, spread(runs, 'tasks', '%d'), spread(runs, 'failed', '%d'),
          spread(runs, 'p50', '%.1f', 1e3), spread(runs, 'p99', '%.1f', 1e3),
          spread(runs, 'p999', '%.1f', 1e3), spread(runs, 'max', '%.0f', 1e3),
          spread(runs, 'second', '%.1f', 100), spread(runs, 'extra', '%.1f', 100))
         for setting, runs in results.items()])


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--delay', type=float, default=5.0, help='one-way ms to server 1 '
                        '(server 2: 1.5 x)')
    parser.add_argument('--loss', type=float, default=0.01)
    parser.add_argument('--rate', type=float, default=10.0)
    parser.add_argument('--seconds', type=float, default=60.0, help='tasks sent per run')
    parser.add_argument('--runs', type=int, default=2)
    args = parser.parse_args(argv)
    results = {'off': [], 'on': []}
    with tempfile.TemporaryDirectory(prefix='bench_hedging') as work:
        for index in range(args.runs):
            for setting, row in run_once(args, work, index).items():
                results[setting].append(row)
                print(table({setting: [row]}).splitlines()[-1], file=sys.stderr,
                      flush=True)
    cli.write(args.out, 'hedging.json', results)
    print('\nSort tasks at %g/s a robot over %g ms one way (server 2: %g ms), %g %% loss each way; '
          'failed tasks counted at %g s; median (min-max) of %d runs\n\n%s\n'
          % (args.rate, args.delay, args.delay * 1.5, 100 * args.loss, TIMEOUT, args.runs,
             table(results)))
    return 0


if __name__ == '__main__':
    sys.exit(main())
