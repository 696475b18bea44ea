"""How soon a simulated fleet is back after a burst (``python3 -m server_select.sim.recovery
config/sim/burst.yaml --seeds 20 --variants fleet,prequal``): the soak's own measure
(:func:`server_select.soak.checks.recovery`) on the simulator's task reports, so that a
recovery the soak misses is reproduced from a seed and a change is judged on paired seeds
before the testbed confirms it.

The fault is the scenario's robots that stop (a burst: from the first of them to start
until the last stops); the fleet is the robots up throughout, back once a window of their
tasks all succeeded with their round trips within the soak's tolerance of the minute before.
"""

import argparse
import collections
import statistics
import sys

from server_select.sim.model import Model
from server_select.sim.run import simulate
from server_select.soak import checks
from server_select.soak.plan import RECOVERY
from server_select.testbed.scenario import Scenario

LIMIT = 30.0     # s after the burst a recovery is looked for (None past it)
# what the soak's check reads of a task report (its bags' reports have more)
Task = collections.namedtuple('Task', 't robot kind ok rtt')


def burst_of(scenario):
    """``(event, [robot ids up throughout])`` of ``scenario``: the event as the soak writes
    one (start, end, bound); ValueError when no robot stops."""
    robots = scenario.of_role('robot')
    bursting = [h for h in robots if h.stop is not None]
    if not bursting:
        raise ValueError('%s: no robot stops, so there is no burst to recover from'
                         % scenario.source)
    event = {'kind': 'overload', 'start': min(h.start for h in bursting),
             'end': max(h.stop for h in bursting), 'bound': RECOVERY}
    return event, [h.id for h in robots if h.stop is None and h.start == 0]


def reports(sim, timeout):
    """The run's task reports as the soak reads them (sent at ``t``; a failed task's round
    trip is the timeout)."""
    return sorted((Task(r.outcome.stamp, r.robot, r.outcome.kind, r.outcome.ok,
                        r.outcome.rtt if r.outcome.ok else timeout) for r in sim.records),
                  key=lambda task: task.t)


def recovery(scenario, model, seed, variant):
    """s from the end of ``scenario``'s burst until ``variant``'s fleet is back (None: not
    within LIMIT s) with ``seed``."""
    event, fleet = burst_of(scenario)
    sim = simulate(scenario, model, seed, [variant])
    back, _ = checks.recovery(reports(sim, sim.timeout), event, [event], set(fleet),
                              event['end'] + LIMIT)
    return back


def main(argv=None):
    parser = argparse.ArgumentParser(prog='recovery', description=__doc__.split('\n\n')[0])
    parser.add_argument('scenario', help='a scenario file whose burst robots stop')
    parser.add_argument('--variants', default='fleet,prequal,oracle_fleet')
    parser.add_argument('--seeds', type=int, default=20)
    args = parser.parse_args(argv)
    scenario, model = Scenario.load(args.scenario), Model.load()
    print('recovery after the burst (s; the soak bound %g s), %d seeds' % (RECOVERY, args.seeds))
    print('| variant | median | p90 | max | over the bound |')
    print('|---|---|---|---|---|')
    for variant in args.variants.split(','):
        found = [recovery(scenario, model, seed, variant) for seed in range(1, args.seeds + 1)]
        times = [LIMIT if t is None else t for t in found]
        ninth = statistics.quantiles(times, n=10)[-1] if len(times) > 1 else times[0]
        print('| %s | %.1f | %.1f | %.1f%s | %d of %d |' % (
            variant, statistics.median(times), ninth, max(times),
            '+' if None in found else '', sum(1 for t in times if t > RECOVERY), len(times)))
    return 0


if __name__ == '__main__':
    sys.exit(main())
