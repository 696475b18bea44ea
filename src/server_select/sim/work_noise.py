"""The work noise of a shared CPU, fitted (no rospy): the model's ``shared_ms`` is the
value on a grid whose simulated loopback demo (``config/sim/loopback.yaml``) gives the
spread of the work servers report that the real one gave
(``bench.loopback_demo``: the standard deviation of the logarithm of the sort work each
server reports to an observer's probes, 2 a second, per server and run).

``python3 -m server_select.sim.work_noise results/bench/loopback_demo.json`` prints the
grid (simulated spread per value, over ``--seeds``) and the value it fits.
"""

import argparse
import copy
import json
import statistics
import sys

from server_select.bench.loopback_demo import PROBE_PERIOD, log_spread
from server_select.ros.paths import package_file
from server_select.sim.model import Model
from server_select.sim.run import Simulation
from server_select.testbed.scenario import Scenario

SCENARIO = ('config', 'sim', 'loopback.yaml')
GRID = [round(0.05 * i, 2) for i in range(0, 21)]     # shared_ms


def reported_spread(model, seed, scenario=None, kind='sort'):
    """The median over servers of the log spread of the ``kind`` work each server of the
    simulated loopback demo reports, sampled as the bench's observer samples it."""
    scenario = scenario or Scenario.load(package_file(*SCENARIO))
    sim = Simulation(scenario, model, seed, ['fleet'])
    reports = dict((server, []) for server in sim.servers)

    def sample():
        for server_id, server in sim.servers.items():
            work = server.queue.load().service.get(kind)
            if work:
                reports[server_id].append(work)
        sim.loop.at(sim.loop.now() + PROBE_PERIOD, sample)

    sim.loop.at(PROBE_PERIOD, sample)
    sim.run()
    spreads = [s for s in (log_spread(w) for w in reports.values()) if s is not None]
    return statistics.median(spreads) if spreads else None


def measured_spread(path):
    """The median over servers and runs of the spreads a ``loopback_demo.json`` holds."""
    with open(path) as stream:
        runs = json.load(stream)['runs']
    return statistics.median(v for r in runs for v in r['work_sigma'].values()
                             if v is not None)


def with_shared(model, shared_ms):
    """A copy of ``model`` with ``shared_ms``."""
    changed = copy.copy(model)
    changed.shared = shared_ms * 1e-3
    return changed


def fit(measured, seeds=range(1, 11), grid=GRID, model=None):
    """``(the grid value whose simulated spread is nearest ``measured``, [(value, median
    simulated spread)])``."""
    model = model or Model.load()
    scenario = Scenario.load(package_file(*SCENARIO))
    rows = [(value, statistics.median(reported_spread(with_shared(model, value), seed, scenario)
                                      for seed in seeds)) for value in grid]
    best = min(rows, key=lambda row: abs(row[1] - measured))[0]
    return best, rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('measured', help='loopback_demo.json of bench.loopback_demo')
    parser.add_argument('--seeds', type=int, default=10)
    args = parser.parse_args(argv)
    measured = measured_spread(args.measured)
    best, rows = fit(measured, seeds=range(1, args.seeds + 1))
    print('measured spread of the reported sort work: %.3f' % measured)
    print('| shared_ms | simulated spread |\n|---|---|')
    for value, spread in rows:
        print('| %.2f | %.3f%s |' % (value, spread, ' (fit)' if value == best else ''))
    print('shared_ms: %.2f' % best)
    return 0


if __name__ == '__main__':
    sys.exit(main())
