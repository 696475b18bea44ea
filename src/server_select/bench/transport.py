"""Raw vs compressed frames over a slow link (testbed, root): bytes, round trip, frames/s.

One robot sends 640x480 camera frames (the search area) at ``--fps`` to one server over a
link of ``--delay`` ms one way and ``--rate`` MB/s each way, once with
``image_transport:=raw`` and once with ``compressed`` (JPEG, ``--quality``), ``--runs``
times each, and prints per transport: frames sent and answered, failed (counted in the
round trip at the task timeout), achieved frames/s, round trip median and p95, and the
bytes on the link per frame each way (the emulator counts them).
"""

import json
import os
import sys
import tempfile

from server_select.bench import cli
from server_select.bench.harness import link_bytes, scenario_run
from server_select.ros.paths import package_file
from server_select.core.util.stats import summarize
from server_select.core.util.tables import markdown_table, median_range
from server_select.testbed import bag_analysis

TIMEOUT = 5.0


def scenario(delay, rate, seconds):
    return {'name': 'transport', 'duration': seconds + 12,
            'hosts': {'manager': {'role': 'manager'}, 'server1': {'role': 'server', 'id': 1},
                      'robot1': {'role': 'robot', 'id': 1}},
            'default': {'delay': 0.5},
            'links': {'robot1 server1': [{'at': 0, 'delay': delay, 'rate': rate}]}}


def run_once(transport, args, work):
    data = scenario(args.delay, args.rate, args.seconds)
    with scenario_run(data, work, transport, 'sstr') as (run, bag):
        run.launch('manager', 'manager.launch', 'robots:=1', 'servers:=1')
        run.launch('server1', 'server.launch', 'server_id:=1')
        run.launch('robot1', 'robot.launch', 'robot_id:=1', 'servers:=1', 'sort_tasks:=false',
                   'image_source:=search:%s' % package_file('config', 'search_area.yaml'),
                   'frame_rate:=%g' % args.fps, 'image_transport:=%s' % transport,
                   'jpeg_quality:=%d' % args.quality, 'task_timeout:=%g' % TIMEOUT,
                   'start_delay:=2', stage=0)
    link = link_bytes(work, transport)
    duration = data['duration']
    reports = bag_analysis.load(bag).reports
    window = [r for r in reports if r.t >= duration - args.seconds - 1]
    return {'sent': len(window), 'ok': sum(1 for r in window if r.ok),
            'fps': sum(1 for r in window if r.ok) / args.seconds,
            'rtt': summarize([r.rtt if r.ok else TIMEOUT for r in window]),
            'up_bytes': link['robot1>server1']['bytes'] / max(1, len(reports)),
            'down_bytes': link['server1>robot1']['bytes'] / max(1, len(reports))}


def table(results):
    def spread(runs, key, fmt, scale=1.0):
        return median_range([scale * (r[key] if not isinstance(key, tuple) else
                                      r[key[0]][key[1]]) for r in runs], fmt)
    return markdown_table(
        ('transport', 'frames sent', 'failed', 'frames/s', 'RTT median ms', 'RTT p95 ms',
         'kB/frame robot->server', 'kB/frame server->robot'),
        [(transport, spread(runs, 'sent', '%d'),
          spread([dict(r, failed=r['sent'] - r['ok']) for r in runs], 'failed', '%d'),
          spread(runs, 'fps', '%.1f'), spread(runs, ('rtt', 'median'), '%.0f', 1e3),
          spread(runs, ('rtt', 'p95'), '%.0f', 1e3), spread(runs, 'up_bytes', '%.0f', 1e-3),
          spread(runs, 'down_bytes', '%.0f', 1e-3)) for transport, runs in results.items()])


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--delay', type=float, default=10.0, help='one-way ms (20 ms RTT)')
    parser.add_argument('--rate', type=float, default=10.0, help='MB/s each way')
    parser.add_argument('--fps', type=float, default=10.0)
    parser.add_argument('--quality', type=int, default=80)
    parser.add_argument('--seconds', type=float, default=20.0, help='measured per run')
    parser.add_argument('--runs', type=int, default=2)
    args = parser.parse_args(argv)
    results = dict((t, []) for t in ('raw', 'compressed'))
    with tempfile.TemporaryDirectory(prefix='bench_transport') as work:
        for _ in range(args.runs):
            for transport in results:
                results[transport].append(run_once(transport, args, work))
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, 'transport.json'), 'w') as stream:
        json.dump(results, stream, indent=1)
    print('\n640x480 frames at %g fps over %g ms one way, %g MB/s each way; median (min-max) '
          'of %d runs, failed tasks counted at %g s\n\n%s\n'
          % (args.fps, args.delay, args.rate, args.runs, TIMEOUT, table(results)))
    return 0


if __name__ == '__main__':
    sys.exit(main())
