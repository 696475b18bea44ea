"""The simulated league (``make league``): every scenario, every variant, paired seeds.

Network scenarios are the suite's files (``testbed/suite.py``); capacity cases are the
capacity benchmark's (``bench/capacity_cases.py``: camera frames to servers of finite
CPU, the offered load a multiple of what the servers can do by the model's CPU per
frame). Each (scenario, variant, seed) is one run of that variant alone on the scenario's
servers; every variant runs every seed, so each sees the same arrivals, links and task
sizes: the report compares them per seed (:mod:`server_select.sim.report`).

``python3 -m server_select.sim.league --seeds 30 --out DIR`` writes ``league.json`` (every
run's figures), ``league.md`` and ``league.png``; ``--scenarios``, ``--variants``,
``--cases``, ``--capacity-variants`` choose cells (a scenario may be a file of yours, or
generated: ``gen:1-200``; a variant may change its robots' parameters,
``fleet:hedge=false``: an ablation). With ``--together`` a network scenario's variants run
side by side on shared servers, as the testbed's suite runs them (one run per seed).
The cells run on dask.distributed (:mod:`~server_select.sim.cells`: ``--scheduler``).
"""

import argparse
import functools
import os
import sys
import time

from server_select.bench.capacity_cases import SCENARIOS as CAPACITY_SCENARIOS
from server_select.bench.capacity_cases import TIMEOUT, WARMUP, scenario as capacity_scenario
from server_select.bench.capacity_report import static_assignment
from server_select.core.peers.balancers import PEERS
from server_select.sim import cells, generate, report
from server_select.sim.figures import figures
from server_select.sim.model import Model
from server_select.sim.run import simulate, variant
from server_select.testbed.scenario import Scenario
from server_select.testbed.suite_scenario import NETWORK, scenario_path, short_name

NETWORK_VARIANTS = ('oracle_fleet', 'fleet') + PEERS
# the league's capacity cases: (the capacity benchmark's case, offered load, its options)
CASES = {
    'overload_unequal': ('overload', 2.0, {'shares': '0.10,0.15,0.20'}),
    'half_unequal': ('overload', 0.5, {'shares': '0.15,0.25,0.40', 'robots': 8}),
    'herd': ('herd', 0.5, {}),
    'herd_20': ('herd', 0.5, {'robots': 20, 'shares': '0.25,0.25,0.25,0.25'}),
}
CAPACITY_VARIANTS = ('static', 'fleet') + PEERS
SECONDS = 30.0         # measured s of a capacity run (the testbed league's)


@functools.lru_cache(maxsize=None)
def _model():
    return Model.load()


@functools.lru_cache(maxsize=None)
def network_scenario(name):
    """A suite scenario's name, a file, or ``gen:<seed>`` (:mod:`~server_select.sim.generate`)."""
    return generate.scenario(name) if name.startswith('gen:') else \
        Scenario.load(scenario_path(name))


@functools.lru_cache(maxsize=None)
def capacity_case(case):
    """``(Scenario, {robot: static server}, frames/s the servers can do)`` of a case."""
    base, load, options = CASES[case]
    spec = dict(CAPACITY_SCENARIOS[base], **options)
    shares = [float(s) for s in spec['shares'].split(',')]
    robots = spec['robots']
    capacity = sum(shares) / _model().kinds['image'][0]
    late = WARMUP + SECONDS / 3.0 if spec.get('late') else None
    data = capacity_scenario(shares, robots, SECONDS, [0.5] * len(shares), late)
    data['name'] = case
    data['suite'] = {'measure_from': WARMUP, 'robot_args': {
        'sort_tasks': False, 'image_source': 'frames', 'frame_rate': load * capacity / robots,
        'task_timeout': TIMEOUT, 'start_delay': 5}}
    return Scenario(data, case), static_assignment(shares, robots), capacity


def run_cell(job):
    """``[(part, scenario, variant, seed, figures dict, CPU s)]`` of one run."""
    part, name, which, seed = job
    start = time.process_time()
    if part == 'together':           # every variant of the scenario side by side
        sim = simulate(network_scenario(name), _model(), seed, which, together=True)
        return [('network', name, v, seed, figures(sim, v)._asdict(),
                 time.process_time() - start) for v in which]
    if part == 'network':
        sim = simulate(network_scenario(name), _model(), seed, [which])
        row = figures(sim, which)._asdict()
    else:
        scenario, fixed, capacity = capacity_case(name)
        sim = simulate(scenario, _model(), seed, [which], fixed=fixed)
        row = figures(sim, which)._asdict()
        row.update(capacity=capacity, work=sim.completed_work())
    return [(part, name, which, seed, row, time.process_time() - start)]


def jobs(args):
    for seed in args.seeds:
        for name in args.scenarios:
            if args.together:
                yield 'together', name, tuple(args.variants), seed
                continue
            for variant_name in args.variants:
                yield 'network', name, variant_name, seed
        for case in args.cases:
            for variant_name in args.capacity_variants:
                yield 'capacity', case, variant_name, seed


def run(args, log=print):
    """Every job of ``args``, on the engine ``args`` names (:mod:`~server_select.sim.cells`):
    ``{part: {scenario: {variant: {seed: figures}}}}`` and the CPU seconds spent."""
    results, cpu = {'network': {}, 'capacity': {}}, 0.0
    for rows in cells.run(run_cell, jobs(args), args.scheduler, args.processes, log):
        for part, name, variant_name, seed, row, seconds in rows:
            results[part].setdefault(short_name(name), {}).setdefault(
                variant_name, {})[seed] = row
            cpu += seconds
    return results, cpu


def _names(text):
    return [x for x in text.split(',') if x]


def parse(argv):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--seeds', type=int, default=30, help='seeds per cell (%(default)s)')
    parser.add_argument('--first-seed', type=int, default=1)
    parser.add_argument('--scenarios', type=_names, default=list(NETWORK))
    parser.add_argument('--variants', type=_names, default=list(NETWORK_VARIANTS))
    parser.add_argument('--cases', type=_names, default=list(CASES))
    parser.add_argument('--capacity-variants', type=_names, default=list(CAPACITY_VARIANTS))
    parser.add_argument('--together', action='store_true', help='network variants side by '
                        'side on shared servers (as the testbed runs them)')
    cells.add_arguments(parser)
    parser.add_argument('--out', default='results/league')
    args = parser.parse_args(argv)
    args.seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    args.scenarios = generate.expand(args.scenarios)
    unknown = [c for c in args.cases if c not in CASES]
    if unknown:
        parser.error('unknown capacity cases %s (of %s)' % (unknown, ', '.join(CASES)))
    for name in args.variants + args.capacity_variants:
        try:
            variant(name)
        except ValueError as error:
            parser.error(str(error))
    return args


def main(argv=None):
    args = parse(sys.argv[1:] if argv is None else argv)
    start = time.monotonic()
    results, cpu = run(args, lambda text: print(text, file=sys.stderr, flush=True))
    results.update(seeds=args.seeds, variants={'network': args.variants,
                                               'capacity': args.capacity_variants},
                   scenarios={'network': [short_name(s) for s in args.scenarios],
                              'capacity': args.cases})
    text = report.write(results, args.out)
    print(text)
    print('%d seeds, %.0f s (%.0f CPU s on %s); %s' % (
        len(args.seeds), time.monotonic() - start, cpu, args.scheduler or '%d processes'
        % args.processes, os.path.join(args.out, 'league.md')))
    return 0


if __name__ == '__main__':
    sys.exit(main())
