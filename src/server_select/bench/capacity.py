"""Capacity: goodput and round trip against offered load, on servers of finite CPU (testbed,
root, cgroup cpu controller).

Robots send camera frames (a 640x480 photograph with a face, JPEG, Haar detection at the
server) or sort tasks to servers whose hosts have a CPU share (a cgroup quota: real work,
really slower). Offered load steps through multiples of the servers' capacity, and each
step is run for each variant in turn (a server's load is part of what is measured, so
variants cannot share servers as the scenario suite's do):

- ``paper``: the paper's profile (the manager ranks by the probes' mean; every frame sent);
- ``fleet``: the fleet profile (load-aware ranking, busy answers, in-flight limit, retry
  budget, spread);
- ``static``: every robot fixed to one server, robots given to servers in proportion to
  their CPU shares (D'Hondt): the best static assignment when links are equal;
- the league's peers (``p2c_peak_ewma``, ``least_request``, ``prequal``, ``round_robin``,
  ``replicate``): the fleet profile with that rule choosing per task
  (:func:`server_select.testbed.suite.peer_params`);
- on request, any other variant of the scenario suite whose robots select on hosts of their
  own (``fleet_6hz``, ``fleet_uniform``, ...): its profile and parameters.

Capacity (tasks/s) is the servers' shares over the CPU seconds one task takes on one core
of this machine, measured here before the runs. Per variant and load the benchmark prints
what was offered and sent, the goodput (tasks answered within the task timeout, per s),
failed tasks, the round trip (mean, p50, p99; a failed task counts at the timeout), the
oldest answer, extra sends per task, and for frames how many detections the servers did
and how many of those a robot still wanted.
"""

import math
import os
import sys
import tempfile
import threading

from server_select.bench import capacity_report, cli
from server_select.bench.capacity_cases import SCENARIOS, TIMEOUT, WARMUP, SETTLE, scenario
from server_select.bench.capacity_report import static_assignment
from server_select.bench.capacity_work import SORT_SIZE, cpu_per_task
from server_select.vision.image_source import write_frame
from server_select.bench.harness import scenario_run
from server_select.testbed import bag_analysis, suite
from server_select.testbed.suite_scenario import server_args

VARIANTS = ('paper', 'fleet', 'static', 'fleet_hysteresis') + suite.RULES
# besides static, any suite variant whose robots select, on hosts of their own
ACCEPTED = ('static',) + tuple(name for name, v in suite.VARIANTS.items()
                               if v.mode == 'select' and not v.host)
# s between the servers' lines of the tasks they worked on, whose counts give the work
# rate: several in the shortest window (12 s), though a line is late on a starved host
SUMMARY_PERIOD = 2.0


def robot_args(kind, rate, folder):
    if kind == 'image':
        return ['sort_tasks:=false', 'image_source:=%s' % folder, 'frame_rate:=%g' % rate,
                'image_transport:=compressed']
    return ['task_rate:=%g' % rate, 'task_size:=%d' % SORT_SIZE]


def run_once(variant, kind, rate, args, work, name):
    """One run: the figures of :func:`capacity_report.figures` for it."""
    shares = args.shares
    servers = ','.join(str(s) for s in range(1, len(shares) + 1))
    late = WARMUP + args.seconds / 3.0 if args.late else None
    data = scenario(shares, args.robots, args.seconds, args.delays, late)
    profile = 'paper' if variant == 'static' else suite.VARIANTS[variant].profile
    given = {} if variant == 'static' else suite.VARIANTS[variant].params
    peer = ['%s:=%s' % (k, str(v).lower()) for k, v in sorted(given.items())]
    fixed = static_assignment(shares, args.robots)
    # the flags and probe samples too: what a robot's moves can be read from
    with scenario_run(data, work, name, 'sscap', record=(
            '/task_report', '/detections', '/server_select_flag',
            '/latency_samples')) as (run, bag):
        if variant != 'static':
            run.launch('manager', 'manager.launch', 'profile:=%s' % profile,
                       'robots:=%s' % ','.join(str(r) for r in range(1, args.robots + 1)),
                       'servers:=%s' % servers, *args.manager_args.split())
        for server in range(1, len(shares) + 1):   # a host's /sys hides its cgroup quota
            args_of = ('server%d' % server, 'server.launch', 'server_id:=%d' % server,
                       'routing:=direct', 'workers:=%d' % math.ceil(shares[server - 1]),
                       'summary_period:=%g' % SUMMARY_PERIOD,
                       'check_every:=%g' % server_args()['check_every'])
            if late is not None and server == len(shares):
                threading.Thread(target=lambda a=args_of: (run.tb.sleep_until(late),
                                                           run.launch(*a)),
                                 daemon=True).start()
            else:
                run.launch(*args_of)
        for robot in range(1, args.robots + 1):
            run.launch('robot%d' % robot, 'robot.launch', 'robot_id:=%d' % robot,
                       'profile:=%s' % profile, 'servers:=%s' % servers,
                       'mode:=%s' % ('fixed' if variant == 'static' else 'select'),
                       'fixed_server:=%d' % fixed[robot], 'task_timeout:=%g' % TIMEOUT,
                       'start_delay:=5', *(robot_args(kind, rate, args.frames) +
                                           peer + args.robot_args.split()), stage=0)
    t0 = run.tb.t0
    done = capacity_report.detections(bag, t0) if kind == 'image' else None
    # each server's tasks/s by its share (frames: the CPU a frame takes is the work; a sort
    # task's is mostly message handling, which is not modelled: no overload figure)
    capacities = dict((s, share / args.cpu) for s, share in enumerate(shares, start=1)) \
        if kind == 'image' else None
    run = bag_analysis.load(bag)
    settled = late + SETTLE if late is not None else capacity_report.placed(run) + SETTLE
    row = capacity_report.figures(run, done, rate * args.robots, WARMUP,
                                  WARMUP + args.seconds, TIMEOUT, capacities, settled)
    row['work'] = capacity_report.work_rate(os.path.join(work, name), t0, WARMUP,
                                            WARMUP + args.seconds)
    return row


def parse(argv):
    parser = cli.parser(__doc__)
    parser.add_argument('--scenario', choices=sorted(SCENARIOS), default='overload',
                        help='a case: its shares, delays, robots, loads and late server are '
                        'the defaults of those options (%(default)s)')
    parser.add_argument('--shares', help="the servers' CPU shares of one core")
    parser.add_argument('--delays', help='one-way link delay to each server, ms (0.5 each)')
    parser.add_argument('--robots', type=int)
    parser.add_argument('--loads', help='offered load as multiples of the capacity')
    parser.add_argument('--kinds', default='image', help='image and/or sort (%(default)s)')
    parser.add_argument('--variants', default=','.join(VARIANTS))
    parser.add_argument('--seconds', type=float, default=40.0, help='measured s per run')
    parser.add_argument('--repeats', type=int, default=1)
    parser.add_argument('--late', action='store_true', default=None, help='the last server '
                        'starts a third of the way into the measured part, idle (herd)')
    parser.add_argument('--work', help='keep the runs (bags, node logs) in this folder')
    parser.add_argument('--robot-args', default='', help='more robot.launch arguments for '
                        'every robot, e.g. "max_in_flight:=1 hedge:=false"')
    parser.add_argument('--manager-args', default='', help='more manager.launch arguments')
    parser.add_argument('--capacity', action='append', default=[], metavar='KIND=RATE',
                        help="the servers' capacity in tasks/s that --loads multiply (default: "
                        'their shares over the CPU a task takes here; a sort task\'s cost is '
                        'mostly message handling, which that leaves out: measure it, e.g. '
                        'with --variants static at a high load, and give it here)')
    args = parser.parse_args(argv)
    for name, value in SCENARIOS[args.scenario].items():
        if getattr(args, name) is None:
            setattr(args, name, value)
    args.shares = [float(s) for s in args.shares.split(',')]
    args.delays = [float(d) for d in (args.delays or ','.join(['0.5'] * len(args.shares)))
                   .split(',')]
    args.loads = [float(x) for x in args.loads.split(',')]
    args.kinds = [k for k in args.kinds.split(',') if k]
    args.variants = [v for v in args.variants.split(',') if v]
    try:
        args.capacity = dict((k, float(v)) for k, v in (c.split('=') for c in args.capacity))
    except ValueError:
        parser.error('--capacity takes KIND=RATE, e.g. sort=40')
    bad = [k for k in args.kinds if k not in ('image', 'sort')] + \
        [v for v in args.variants if v not in ACCEPTED]
    if bad or args.robots < 1 or not args.shares or len(args.delays) != len(args.shares):
        parser.error('unknown kinds or variants %s, no robots or servers, or not one delay '
                     'per server' % bad)
    return args


def main(argv=None):
    args = parse(sys.argv[1:] if argv is None else argv)
    results = {'scenario': args.scenario, 'shares': args.shares, 'delays': args.delays,
               'late': bool(args.late), 'robots': args.robots, 'timeout': TIMEOUT,
               'seconds': args.seconds, 'kinds': {}}
    with tempfile.TemporaryDirectory(prefix='bench_capacity') as scratch:
        work = args.work or scratch
        args.frames = os.path.join(work, 'frames')
        write_frame(args.frames)
        for kind in args.kinds:
            cpu = args.cpu = cpu_per_task(kind)
            capacity = args.capacity.get(kind, sum(args.shares) / cpu)
            runs = results['kinds'][kind] = {'cpu_per_task': cpu, 'capacity': capacity,
                                             'runs': []}
            print('%s: %.1f ms of CPU per task: capacity %.2f tasks/s' % (
                kind, 1e3 * cpu, capacity), file=sys.stderr, flush=True)
            for repeat in range(args.repeats):
                for load in args.loads:
                    for variant in args.variants:
                        name = '%s-%s-%g-%d' % (kind, variant, load, repeat)
                        row = run_once(variant, kind, load * capacity / args.robots, args,
                                       work, name)
                        row.update(variant=variant, load=load, repeat=repeat)
                        runs['runs'].append(row)
                        print(capacity_report.line(row), file=sys.stderr, flush=True)
    stem = 'capacity_' + args.scenario
    cli.write(args.out, stem + '.json', results)
    text = capacity_report.report(results, os.path.join(args.out, stem + '.png'))
    cli.write(args.out, stem + '.md', text)
    print(text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
