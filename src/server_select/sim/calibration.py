"""The simulator beside the testbed (``make calibrate``): the testbed league's medians
(``config/sim/testbed.yaml``) against the simulator's on the same cells.

Network scenarios run as the testbed ran them: every league variant side by side on
shared servers (``together``); capacity cases as the league runs them (each variant
alone: mean, goodput share, switches a minute per robot and the share of the servers'
work a robot still wanted); the loopback demo (``config/sim/loopback.yaml``: switches a
minute per robot among identical servers on one host once settled, and how far a probe's
round trip strays there, ``probe_mad``: the median absolute deviation, ms). Targets: each
simulated median within 10 % of the testbed's or inside the testbed's min-max, and every
ordering of two variants that the testbed shows beyond its spread (their min-max ranges
apart) kept by the simulator's medians. ``--hop-ms``, ``--probe-ms`` and ``--cpu-factor`` try
other model constants (``config/sim/model.yaml`` keeps the chosen ones).
"""

import argparse
import functools
import itertools
import os
import statistics
import sys

import yaml

from server_select.bench.loopback_demo import probe_spread
from server_select.core.util.tables import markdown_table
from server_select.ros.paths import package_file
from server_select.sim import cells, league
from server_select.sim.figures import figures
from server_select.sim.model import Model
from server_select.sim.run import simulate
from server_select.sim.stats import median_interval
from server_select.testbed.scenario import Scenario

TARGET = 0.10
PARTS = ('network', 'capacity', 'loopback')
FIGURES = ('mean', 'share', 'switches', 'wanted', 'probe_mad')
SIDE_BY_SIDE = league.NETWORK_VARIANTS      # the testbed's league, less its old rule


def _network(job):
    name, seed, constants = job
    model = _model(constants)
    sim = simulate(league.network_scenario(name), model, seed, SIDE_BY_SIDE, together=True)
    return ('network', name, seed, dict((v, figures(sim, v).mean) for v in SIDE_BY_SIDE))


def _capacity(job):
    case, variant, seed, constants = job
    scenario, fixed, capacity = league.capacity_case(case)
    sim = simulate(scenario, _model(constants), seed, [variant], fixed=fixed)
    row = figures(sim, variant)
    return ('capacity', case, seed, {variant: {
        'mean': 1e3 * row.mean, 'share': 100 * row.goodput / capacity,
        'switches': row.switches, 'wanted': 100 * row.wanted}})


def _loopback(job):
    _, variant, seed, constants = job
    scenario = Scenario.load(package_file('config', 'sim', 'loopback.yaml'))
    sim = simulate(scenario, _model(constants), seed, [variant])
    spread = probe_spread(sim.probe_rtts.values())
    return ('loopback', 'loopback', seed, {variant: {
        'switches': figures(sim, variant).switches, 'probe_mad': spread}})


@functools.lru_cache(maxsize=None)
def _model(constants):
    model = Model.load()
    hop, probe, factor = constants
    if hop is not None:
        model.hop = hop * 1e-3
    if probe is not None:
        model.probe_cpu = probe * 1e-3
    if factor is not None:
        model.cpu_factor = factor
    return model


def _run(job):
    return _network(job) if job[0] in league.NETWORK else \
        _loopback(job) if job[0] == 'loopback' else _capacity(job)


def measure(reference, seeds, constants, scheduler=None, processes=None):
    """``{(part, scenario, variant): {figure: [per seed]}}`` of the simulator (its cells on
    :mod:`~server_select.sim.cells`)."""
    jobs = [(name, seed, constants) for name in reference['network'] for seed in seeds]
    jobs += [(case, variant, seed, constants) for case, variants in
             reference['capacity'].items() for variant in variants for seed in seeds]
    jobs += [('loopback', variant, seed, constants) for variant in
             reference.get('loopback', {}).get('loopback', {}) for seed in seeds]
    sims = {}
    log = functools.partial(print, file=sys.stderr, flush=True)
    for part, name, seed, values in cells.run(_run, jobs, scheduler, processes, log):
        for variant, value in values.items():
            figures_of = sims.setdefault((part, name, variant), {})
            for figure, number in (value.items() if isinstance(value, dict)
                                   else [('mean', 1e3 * value)]):
                figures_of.setdefault(figure, []).append(number)
    return sims


def close(sim, median, low, high):
    """Whether a simulated median is within 10 % of the testbed's, or inside its
    min-max."""
    return low <= sim <= high or (median != 0 and abs(sim / median - 1.0) <= TARGET)


def compare(reference, sims):
    """``(table rows, misses, orderings checked, orderings kept)``."""
    rows, misses, checked, kept, orderings = [], 0, 0, 0, []
    for part in PARTS:
        for name, variants in reference.get(part, {}).items():
            for figure in FIGURES:
                cells = dict((v, f[figure]) for v, f in variants.items() if figure in f)
                for variant, (median, low, high) in cells.items():
                    sim = median_interval(sims[(part, name, variant)][figure])
                    ok = close(sim[0], median, low, high)
                    misses += not ok
                    rows.append(['%s %s' % (name, figure if figure != 'mean' else ''), variant,
                                 '%.4g (%.4g-%.4g)' % (median, low, high),
                                 '%.4g [%.4g-%.4g]' % sim,
                                 '%.3f' % (sim[0] / median) if median else '-',
                                 'yes' if ok else '**no**'])
                for a, b in itertools.permutations(cells, 2):
                    if cells[a][2] < cells[b][1]:          # a below b beyond the spread
                        checked += 1
                        held = statistics.median(sims[(part, name, a)][figure]) < \
                            statistics.median(sims[(part, name, b)][figure])
                        kept += held
                        orderings.append('%s %s: %s < %s %s' % (
                            name, figure, a, b, 'kept' if held else '**not kept**'))
    return rows, misses, checked, kept, orderings


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--seeds', type=int, default=10)
    parser.add_argument('--hop-ms', type=float)
    parser.add_argument('--probe-ms', type=float)
    parser.add_argument('--cpu-factor', type=float)
    parser.add_argument('--part', choices=('all',) + PARTS, default='all')
    cells.add_arguments(parser)
    parser.add_argument('--out', help='also write calibration.md here')
    args = parser.parse_args(argv)
    with open(package_file('config', 'sim', 'testbed.yaml')) as stream:
        reference = yaml.safe_load(stream)
    for part in PARTS:
        if args.part not in ('all', part):
            reference[part] = {}
    sims = measure(reference, range(1, args.seeds + 1),
                   (args.hop_ms, args.probe_ms, args.cpu_factor), args.scheduler,
                   args.processes)
    rows, misses, checked, kept, orderings = compare(reference, sims)
    text = markdown_table(['cell', 'variant', 'testbed median (min-max)',
                           'simulator median [95 % interval]', 'sim / testbed',
                           'within 10 % or min-max'], rows)
    text += '\n\n%d of %d cells within 10 %% or the testbed\'s min-max; %d of %d orderings ' \
        'the testbed shows beyond its spread kept (%d seeds):\n\n' % (
            len(rows) - misses, len(rows), kept, checked, args.seeds)
    text += '\n'.join('- ' + line for line in orderings) + '\n'
    print(text)
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, 'calibration.md'), 'w') as stream:
            stream.write(text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
