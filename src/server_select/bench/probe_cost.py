"""Probe cost: probes per robot per second and robot CPU, uniform vs adaptive probing.

For each number of servers (``--servers``, e.g. 10,50,100) and each variant, side by side
in one run and repeated (``--repeats``): a roscore of its own, one process that serves
``latency_S1`` ... ``latency_S<n>`` (each answering after its own delay: server 1 at 2.0 ms,
server 2 at 2.3 ms, the others from 4 ms up by 0.5 ms a server: two contenders and a
fleet of farther servers) and counts the calls it answers, and one real robot node with
the fleet profile (its tasks worked locally at 0.2 Hz, so that the robot's CPU is its
probing and ranking). ``uniform`` probes every server at the fleet's 4 Hz
(``contender_rate:=0``); ``adaptive`` is the fleet profile (contenders at
``~contender_rate``, the others at ``~background_rate``). After ``--warmup`` s, over
``--measure`` s: the calls the servers answered per second (all, and to the two nearest
servers) and the robot's CPU % of one core. Prints a Markdown table (median of the
repeats, min-max) and the target ``20 + 0.5 x servers``; writes JSON. Nothing is asserted.

    python3 -m server_select.bench.probe_cost --servers 10,50,100 --repeats 3
"""

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time

import rospy

from server_select.bench import cli
from server_select.bench.harness import Roscore, pid_or_none
from server_select.core.config import names
from server_select.core.util.procs import measure, stop_groups, wait_until
from server_select.core.util.tables import markdown_table, median_range
from server_select.srv import LatencyProbe, LatencyProbeResponse

VARIANTS = {'uniform': ['_contender_rate:=0'], 'adaptive': []}


def delay(server):
    """Seconds server ``server`` takes to answer a probe."""
    return {1: 0.0020, 2: 0.0023}.get(server, 0.004 + 0.0005 * (server - 3))


def serve(count, path):
    """Serve ``count`` probe services in this process; write the calls answered to
    ``path`` (JSON, ``{server: calls}``) every 0.5 s until shut down."""
    rospy.init_node('probe_servers', disable_signals=False)
    calls, lock = dict((s, 0) for s in range(1, count + 1)), threading.Lock()

    def handler(server):
        def answer(request):
            time.sleep(delay(server))
            with lock:
                calls[server] += 1
            return LatencyProbeResponse(server_id=server, seq=request.seq, stamp=request.stamp,
                                        server_stamp=rospy.Time.now(), workers=1)
        return answer

    services = [rospy.Service(names.probe_service(s), LatencyProbe, handler(s))
                for s in calls]
    while not rospy.is_shutdown():
        with lock:
            text = json.dumps(calls)
        with open(path + '.tmp', 'w') as stream:
            stream.write(text)
        os.replace(path + '.tmp', path)
        time.sleep(0.5)
    for service in services:
        service.shutdown()


def _read(path):
    try:
        with open(path) as stream:
            return dict((int(k), v) for k, v in json.load(stream).items())
    except (OSError, ValueError):
        return None


def _node(args, log):
    with open(log, 'a') as stream:
        return subprocess.Popen([sys.executable] + args, stdout=stream,
                                stderr=subprocess.STDOUT, start_new_session=True)


def one_run(servers, variant, warmup, seconds, tmp):
    """One measurement: {'probes', 'near', 'cpu'} (per second, per second, % of a core)."""
    counts = os.path.join(tmp, 'calls_%d_%s.json' % (servers, variant))
    log = os.path.join(tmp, 'nodes.log')
    ids = ','.join(str(s) for s in range(1, servers + 1))
    with Roscore(tmp):
        procs = [_node(['-m', 'server_select.bench.probe_cost', '--serve', str(servers),
                        '--calls', counts], log)]
        try:
            if not wait_until(lambda: _read(counts) is not None, 60.0, period=0.2):
                raise RuntimeError('the probe servers did not start (%s)' % log)
            procs.append(_node(['-c', 'from server_select.nodes.robot import main; main()',
                                '__name:=robot1', '_robot_id:=1', '_servers:=%s' % ids,
                                '_profile:=fleet', '_discover:=false', '_mode:=local',
                                '_task_rate:=0.2'] + VARIANTS[variant], log))
            if not wait_until(lambda: pid_or_none('/robot1') is not None, 60.0, period=0.2):
                raise RuntimeError('the robot did not start (%s)' % log)
            time.sleep(warmup)
            before = _read(counts)
            usage = measure([pid_or_none('/robot1')], seconds)
            after = _read(counts)
        finally:
            stop_groups(procs, signal.SIGINT)
    calls = dict((s, after[s] - before[s]) for s in after)
    cpu = next(iter(usage.values()))['cpu_percent'] if usage else None
    return {'probes': sum(calls.values()) / seconds,
            'near': (calls.get(1, 0) + calls.get(2, 0)) / seconds, 'cpu': cpu}


def table(results):
    rows = []
    for servers in sorted(set(r['servers'] for r in results)):
        for variant in VARIANTS:
            runs = [r for r in results if r['servers'] == servers and r['variant'] == variant]
            cpus = [r['cpu'] for r in runs if r['cpu'] is not None]
            rows.append([servers, variant, median_range([r['probes'] for r in runs]),
                         median_range([r['near'] for r in runs]),
                         median_range(cpus) if cpus else 'n/a',
                         '%g' % (20 + 0.5 * servers)])
    return markdown_table(['servers', 'probing', 'probes/s', 'to the 2 nearest /s',
                           'robot CPU %', 'target probes/s'], rows)


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--servers', default='10,50,100', help='numbers of servers')
    parser.add_argument('--repeats', type=int, default=3)
    parser.add_argument('--warmup', type=float, default=8.0, help='s before measuring')
    parser.add_argument('--seconds', type=float, default=20.0, help='s measured')
    parser.add_argument('--serve', type=int, help=argparse.SUPPRESS)
    parser.add_argument('--calls', help=argparse.SUPPRESS)
    args, _ros = parser.parse_known_args(argv)
    if args.serve:
        return serve(args.serve, args.calls)
    results = []
    with tempfile.TemporaryDirectory(prefix='probe_cost_') as tmp:
        for repeat in range(args.repeats):
            for servers in [int(n) for n in args.servers.split(',')]:
                for variant in VARIANTS:   # side by side, one after the other
                    run = one_run(servers, variant, args.warmup, args.seconds, tmp)
                    run.update(servers=servers, variant=variant, repeat=repeat + 1)
                    print('servers %d, %s, repeat %d: %.1f probes/s (%.1f to the 2 nearest), '
                          'robot CPU %s %%' % (servers, variant, repeat + 1, run['probes'],
                                               run['near'], '%.1f' % run['cpu']
                                               if run['cpu'] is not None else 'n/a'),
                          flush=True)
                    results.append(run)
    text = table(results)
    print('\nProbe cost, one robot (fleet profile), median of %d runs (min-max), %g s each\n\n%s'
          % (args.repeats, args.seconds, text))
    cli.write(args.out, 'probe_cost.json', results)
    cli.write(args.out, 'probe_cost.md', text + '\n')


if __name__ == '__main__':
    main()
