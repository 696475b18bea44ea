"""Scale of the real manager node: how many robots x servers before it falls behind.

For each size R x S and sample layout, a roscore of its own, ``--sims`` processes of
simulated robots (:mod:`server_select.bench.scale_sim`: one probe round per robot per
second, flags watched) and the real manager node (``--layout robot``: the fleet
profile's ``latency_samples`` batches; ``pair``: the paper's ``latency_R<r>S<s>``
topics). Printed per run: time from the manager's start until every robot has a flag
ranking all S servers, sample-to-flag delay p50 / p99 (a 10 s round trip for a robot's
selected server, to the flag that moves it), the manager's CPU % of one core, threads,
file descriptors and RSS, and rosmaster's CPU %, measured over ``--measure`` s once every
robot is ranked. A size that is not ranked within ``--limit`` s is reported as such with
what the manager used meanwhile. Nothing is asserted.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import psutil

from server_select.bench.harness import PY, Roscore, node_pid
from server_select.core.procs import measure, stop_group, wait_until
from server_select.core.stats import summarize
from server_select.core.tables import fmt as _fmt, markdown_table

SIZES = '2x3,10x10,50x50,100x50,200x100,500x100'


def _manager(layout, robots, servers, log):
    cmd = [sys.executable, '-c', 'from server_select.nodes.manager import main; main()',
           '_robots:=%s' % ','.join(map(str, robots)),
           '_servers:=%s' % ','.join(map(str, servers)), "_robot_node:='*'",
           '_sample_stream:=%s' % layout, '_discover:=false', '__name:=manager']
    with open(log, 'a') as stream:
        return subprocess.Popen(cmd, stdout=stream, stderr=subprocess.STDOUT,
                                start_new_session=True)


def _sims(tmp, robots, servers, sims, layout, until, log):
    per = -(-robots // sims)
    procs, outs = [], []
    for first in range(1, robots + 1, per):
        out = os.path.join(tmp, 'sim%d.json' % first)
        cmd = PY + ['server_select.bench.scale_sim', '--first', str(first), '--count',
                    str(min(per, robots - first + 1)), '--servers', str(servers),
                    '--layout', layout, '--until', repr(until), '--out', out]
        with open(log, 'a') as stream:
            procs.append(subprocess.Popen(cmd, stdout=stream, stderr=subprocess.STDOUT,
                                          start_new_session=True))
        outs.append(out)
    return procs, outs


def _usage(pid):
    proc = psutil.Process(pid)
    with proc.oneshot():
        return {'threads': proc.num_threads(), 'fds': proc.num_fds(),
                'rss_mb': proc.memory_info().rss / 2.0 ** 20}


def _ranked_in(outs):
    """Latest first-full-ranking time over every robot (None if one never got one)."""
    ranked, robots, delays = [], 0, []
    for out in outs:
        with open(out) as stream:
            data = json.load(stream)
        ranked += list(data['ranked'].values())
        robots += data['robots']
        delays += data['delays']
    return (max(ranked) if len(ranked) == robots and ranked else None), delays


def run_one(robots, servers, layout, sims, limit, measure_s, tmp):
    log = os.path.join(tmp, 'scale.log')
    until = time.time() + 8.0 + limit + measure_s
    sim_procs, outs = _sims(tmp, robots, servers, sims, layout, until, log)
    time.sleep(5.0)                    # the simulated robots registered and publishing
    started = time.time()
    manager = _manager(layout, range(1, robots + 1), range(1, servers + 1), log)
    row = {'robots': robots, 'servers': servers, 'layout': layout}
    try:
        if not wait_until(lambda: _pid('/manager') is not None, 30.0, period=0.2):
            with open(log) as stream:
                raise RuntimeError('the manager did not register:\n' + stream.read()[-3000:])
        pids = {'manager': _pid('/manager'), 'rosmaster': _master_pid()}
        time.sleep(max(0.0, started + limit - time.time()))
        usage = measure([p for p in pids.values() if p], measure_s)
        row.update(_usage(pids['manager']))
        row['manager_cpu'] = usage.get(pids['manager'], {}).get('cpu_percent')
        row['master_cpu'] = usage.get(pids['rosmaster'], {}).get('cpu_percent')
    finally:
        for proc in sim_procs:
            proc.wait(timeout=limit + measure_s + 60)
        stop_group(manager)
    last, delays = _ranked_in(outs)
    row['ranked_s'] = None if last is None else last - started
    summary = summarize(delays)
    row['delay_p50_ms'] = summary['median'] * 1e3 if delays else None
    row['delay_p99_ms'] = summary['p99'] * 1e3 if delays else None
    row['changes'] = len(delays)
    return row


def _pid(node):
    try:
        return node_pid(node)
    except Exception:  # not registered (yet)
        return None


def _master_pid():
    for proc in psutil.process_iter(['cmdline']):
        cmdline = proc.info['cmdline'] or []
        if any('rosmaster' in c for c in cmdline[:2]) and \
                os.environ['ROS_MASTER_URI'].rsplit(':', 1)[1] in ' '.join(cmdline):
            return proc.pid
    return None


def fmt(value, spec='%.0f'):
    return _fmt(value, spec)


def table(rows):
    header = ['robots x servers', 'samples', 'every robot ranked after', 'sample-to-flag p50 ms',
              'p99 ms', 'changes', 'manager CPU %', 'threads', 'fds', 'RSS MiB', 'rosmaster CPU %']
    body = [['%d x %d' % (r['robots'], r['servers']),
             'per pair' if r['layout'] == 'pair' else 'per robot',
             'never within %.0f s' % r['limit'] if r['ranked_s'] is None
             else '%.1f s' % r['ranked_s'],
             fmt(r['delay_p50_ms'], '%.1f'), fmt(r['delay_p99_ms'], '%.1f'), str(r['changes']),
             fmt(r.get('manager_cpu')), fmt(r.get('threads'), '%d'), fmt(r.get('fds'), '%d'),
             fmt(r.get('rss_mb')), fmt(r.get('master_cpu'))] for r in rows]
    return markdown_table(header, body)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--sizes', default=SIZES, help='RxS,... (default %(default)s)')
    parser.add_argument('--layouts', default='pair,robot')
    parser.add_argument('--pair-max', type=int, default=2500,
                        help='largest R*S run per pair (the layout breaks before)')
    parser.add_argument('--sims', type=int, default=4, help='simulated robot processes')
    parser.add_argument('--limit', type=float, default=30.0,
                        help='seconds for every robot to be ranked')
    parser.add_argument('--measure', type=float, default=15.0)
    parser.add_argument('--out', default='results/bench')
    args = parser.parse_args(argv)
    rows = []
    for size in args.sizes.split(','):
        robots, servers = map(int, size.lower().split('x'))
        for layout in args.layouts.split(','):
            if layout == 'pair' and robots * servers > args.pair_max:
                continue
            with tempfile.TemporaryDirectory(prefix="bench_scale") as tmp, Roscore(tmp):
                print('scale: %d x %d per %s' % (robots, servers, layout), file=sys.stderr,
                      flush=True)
                row = run_one(robots, servers, layout, min(args.sims, robots), args.limit,
                              args.measure, tmp)
                row['limit'] = args.limit
                rows.append(row)
                print(table([row]).splitlines()[-1], file=sys.stderr, flush=True)
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, 'scale.json'), 'w') as stream:
        json.dump(rows, stream, indent=2)
    print(table(rows))


if __name__ == '__main__':
    main()
