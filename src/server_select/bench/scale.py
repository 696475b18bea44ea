"""Scale of the real manager node: how many robots x servers before it falls behind.

For each size R x S and sample layout, a roscore of its own, ``--sims`` processes of
simulated robots (:mod:`server_select.bench.scale_sim`: ``--rate`` probe rounds per robot per
second, flags watched) and the real manager node (``--layout robot``: the fleet
profile's ``latency_samples`` batches; ``pair``: the paper's ``latency_R<r>S<s>``
topics). Printed per run: time from the manager's start until every robot has a flag
ranking all S servers, sample-to-flag delay p50 / p99 (a 10 s round trip for a robot's
selected server, to the flag that moves it), the manager's CPU % of one core, threads,
file descriptors and RSS, and rosmaster's CPU %, measured over ``--measure`` s once every
robot is ranked. A size that is not ranked within ``--limit`` s is reported as such with
what the manager used meanwhile. ``--profile fleet`` runs the manager(s) with the fleet
profile's defaults (window 1.5 s, the hysteresis policy and its robust errors, passive
samples and task memory; the robot and server lists stay fixed) and ``--rate`` sets the
simulated probe rounds per robot and second (the fleet probes at 4 Hz). ``--flag-stream``
(default: the profile's) sends the flags on the shared ``server_select_flag``, which every
robot hears, or on each robot's own topic: the flags and flag bytes that reach a robot per
second are printed. Nothing is asserted.
"""

import itertools
import os
import signal
import sys
import tempfile
import time

import psutil

from server_select.bench import cli
from server_select.bench.harness import Roscore, pid_or_none
from server_select.bench.scale_fleet import (sim_progress, sim_received, start_managers,
                                             start_sims)
from server_select.core.util.procs import measure, stop_groups, wait_until
from server_select.core.trust.keys import make_key
from server_select.core.settings import default
from server_select.core.util.stats import summarize
from server_select.core.util.tables import fmt, markdown_table

SIZES = '2x3,10x10,50x50,100x50,200x100,500x100'
GROUPED = '200x100:4,500x500:10,1000x1000:20'


def _usage(pid):
    proc = psutil.Process(pid)
    with proc.oneshot():
        return {'threads': proc.num_threads(), 'fds': proc.num_fds(),
                'rss_mb': proc.memory_info().rss / 2.0 ** 20}


def run_one(robots, servers, layout, sims, limit, measure_s, tmp, groups=1, profile='paper',
            rate=1.0, key=None, flag_stream='shared'):
    """One size: the simulated robots registered, the manager(s) started; once every robot
    is ranked (at most ``limit`` s) the managers measured for ``measure_s`` s, then (at most
    ``limit`` s more) until a flag change was timed; the row of figures."""
    log = os.path.join(tmp, 'scale.log')
    # the latest the simulated robots run, should this process die without stopping them
    until = time.time() + 120.0 + 2 * limit + measure_s
    started_sims = start_sims(tmp, robots, servers, sims, layout, until, log, groups, rate, key,
                              flag_stream)
    outs = [out for _, out in started_sims.values()]
    row = {'robots': robots, 'servers': servers, 'layout': layout, 'groups': groups,
           'profile': profile, 'rate': rate, 'signed': bool(key), 'flag_stream': flag_stream}
    managers = {}
    try:
        _registered(started_sims, log, 'a simulated robot')
        started = time.time()
        managers = start_managers(layout, robots, servers, groups, log, profile, key, flag_stream)
        _registered(managers, log, 'a manager')
        pids = [pid_or_none(n) for n in managers]
        master = _master_pid()
        wait_until(lambda: sim_progress(outs)[0] is not None,
                   max(0.0, started + limit - time.time()), period=0.2)
        before, began = sim_received(outs), time.time()
        usage = measure(pids + [master], measure_s)
        time.sleep(0.6)       # the result files are rewritten every 0.5 s
        after, span = sim_received(outs), time.time() - began
        row['flags_per_robot_s'] = (after[0] - before[0]) / span / robots
        row['flag_bytes_per_robot_s'] = (after[1] - before[1]) / span / robots
        totals = [_usage(p) for p in pids]
        for name in ('threads', 'fds', 'rss_mb'):      # (key: the fleet key's file)
            row[name] = sum(t[name] for t in totals)
        cpu = [usage.get(p, {}).get('cpu_percent', 0.0) for p in pids]
        row['manager_cpu'], row['manager_cpu_max'] = sum(cpu), max(cpu)
        row['master_cpu'] = usage.get(master, {}).get('cpu_percent')
        if sim_progress(outs)[0] is not None:
            wait_until(lambda: sim_progress(outs)[1], limit, period=0.2)
    finally:
        stop_groups([proc for proc, _ in started_sims.values()], signal.SIGTERM)
        stop_groups(managers.values())
    last, delays = sim_progress(outs)
    row['ranked_s'] = None if last is None else last - started
    summary = summarize(delays)
    row['delay_p50_ms'] = summary['median'] * 1e3 if delays else None
    row['delay_p99_ms'] = summary['p99'] * 1e3 if delays else None
    row['changes'] = len(delays)
    return row


def _registered(nodes, log, what):
    """Wait until every node of ``nodes`` (names) is registered with the master."""
    if not wait_until(lambda: all(pid_or_none(n) for n in nodes), 60.0, period=0.2):
        with open(log) as stream:
            raise RuntimeError('%s did not register:\n%s' % (what, stream.read()[-3000:]))


def _master_pid():
    for proc in psutil.process_iter(['cmdline']):
        cmdline = proc.info['cmdline'] or []
        if any('rosmaster' in c for c in cmdline[:2]) and \
                os.environ['ROS_MASTER_URI'].rsplit(':', 1)[1] in ' '.join(cmdline):
            return proc.pid
    return None


def _layout(row):
    if row['layout'] == 'grouped':
        text = 'grouped: %d x %d servers' % (row['groups'], row['servers'] // row['groups'])
    else:
        text = {'pair': 'per pair', 'view': "robots' own rankings"}.get(row['layout'],
                                                                        'per robot')
    profile, rate = row.get('profile', 'paper'), row.get('rate', 1.0)
    if (profile, rate) != ('paper', 1.0):
        text += ' (%s profile, %g Hz)' % (profile, rate)
    return text + (', signed' if row.get('signed') else '')


def table(rows):
    header = ['robots x servers', 'samples', 'flags', 'every robot ranked after',
              'sample-to-flag p50 ms', 'p99 ms', 'changes', 'managers CPU % (busiest)',
              'threads', 'fds', 'RSS MiB', 'rosmaster CPU %', 'flags to a robot /s',
              'flag bytes to a robot /s']
    body = [['%d x %d' % (r['robots'], r['servers']), _layout(r),
             'per robot' if r.get('flag_stream') == 'robot' else 'shared',
             'never within %.0f s' % r['limit'] if r['ranked_s'] is None
             else '%.1f s' % r['ranked_s'],
             fmt(r['delay_p50_ms'], '%.1f'), fmt(r['delay_p99_ms'], '%.1f'), str(r['changes']),
             '%s (%s)' % (fmt(r.get('manager_cpu'), '%.0f'),
                          fmt(r.get('manager_cpu_max'), '%.0f')),
             fmt(r.get('threads'), '%d'), fmt(r.get('fds'), '%d'),
             fmt(r.get('rss_mb'), '%.0f'), fmt(r.get('master_cpu'), '%.0f'),
             fmt(r.get('flags_per_robot_s'), '%.1f'),
             fmt(r.get('flag_bytes_per_robot_s'), '%.0f')] for r in rows]
    return markdown_table(header, body)


def _sizes(args):
    """(robots, servers, layout, groups) of every run asked for."""
    runs = []
    for size in filter(None, args.sizes.split(',')):
        robots, servers = map(int, size.lower().split('x'))
        runs += [(robots, servers, layout, 1) for layout in args.layouts.split(',')
                 if layout != 'pair' or robots * servers <= args.pair_max]
    for size in filter(None, args.grouped_sizes.split(',')):
        shape, groups = size.split(':')
        robots, servers = map(int, shape.lower().split('x'))
        runs.append((robots, servers, 'grouped', int(groups)))
    return runs


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--sizes', default=SIZES, help='RxS,... (default %(default)s)')
    parser.add_argument('--layouts', default='pair,robot')
    parser.add_argument('--grouped-sizes', default=GROUPED,
                        help='RxS:G,... run grouped, G groups (default %(default)s)')
    parser.add_argument('--pair-max', type=int, default=2500,
                        help='largest R*S run per pair (the layout breaks before)')
    parser.add_argument('--sims', type=int, default=4, help='simulated robot processes')
    parser.add_argument('--limit', type=float, default=30.0,
                        help='seconds for every robot to be ranked')
    parser.add_argument('--measure', type=float, default=15.0)
    parser.add_argument('--profile', choices=('paper', 'fleet'), default='paper',
                        help="the manager's profile (default %(default)s)")
    parser.add_argument('--rate', type=float, default=1.0,
                        help='probe rounds per simulated robot and second (default 1)')
    parser.add_argument('--signed', default='off', help='off, on or off,on: the samples and '
                        "flags unsigned and / or signed with a fleet key (each size both ways "
                        'with off,on)')
    parser.add_argument('--flag-stream', default='',
                        help="shared, robot or shared,robot (default: the profile's)")
    args = parser.parse_args(argv)
    streams = (args.flag_stream or default('flag_stream', args.profile)).split(',')
    rows = []
    for (robots, servers, layout, groups), signed, stream in itertools.product(
            _sizes(args), args.signed.split(','), streams):
        with tempfile.TemporaryDirectory(prefix='bench_scale') as tmp, Roscore(tmp):
            print('scale: %d x %d %s%s, flags %s' % (
                robots, servers, layout, ' signed' * (signed == 'on'), stream),
                file=sys.stderr, flush=True)
            key = os.path.join(tmp, 'fleet.key') if signed == 'on' else None
            if key:
                make_key(key)
            row = run_one(robots, servers, layout, min(args.sims, robots), args.limit,
                          args.measure, tmp, groups, args.profile, args.rate, key, stream)
            row['limit'] = args.limit
            rows.append(row)
            print(table([row]).splitlines()[-1], file=sys.stderr, flush=True)
    cli.write(args.out, 'scale.json', rows)
    print(table(rows))


if __name__ == '__main__':
    main()
