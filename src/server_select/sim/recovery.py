"""How soon a simulated fleet is back after a burst (``python3 -m server_select.sim.recovery
config/sim/burst.yaml --variants fleet,prequal``): the soak's own measure
(:func:`server_select.soak.checks.recovery`) on the simulator's task reports, so that a
recovery the soak misses is reproduced from a seed and a change is judged on paired seeds
before the testbed confirms it.

Each variant after the first is compared with it seed by seed (the mean difference, its
95 % interval, and how many seeds it made sooner and later); ``--out FILE`` keeps the
per-seed times, and ``--against FILE`` compares each variant with the same variant of a
kept run (another commit's code, run from its checkout). 40 seeds by default: a change
that 20 seeds scored p90 2.9 -> 1.9 s and max 7.2 -> 3.5 made seeds 21-40 later, and
came to +0.18 s [-0.36, +0.72] over 40.

The fault is the scenario's robots that stop (a burst: from the first of them to start
until the last stops), or else its first server hang (the soak's ``server_stop``); the fleet
is the robots up throughout, back once a window of their tasks all succeeded with their
round trips within the soak's tolerance of the minute before.
"""

import argparse
import collections
import json
import statistics
import sys

from server_select.sim.model import Model
from server_select.sim.run import simulate
from server_select.sim.stats import paired
from server_select.soak import checks
from server_select.soak.plan import RECOVERY
from server_select.testbed.scenario import Scenario

LIMIT = 30.0     # s after the fault a recovery is looked for (None past it)
# what the soak's check reads of a task report (its bags' reports have more)
Task = collections.namedtuple('Task', 't robot kind ok rtt')


def fault_of(scenario):
    """``(event, [robot ids up throughout])`` of ``scenario``'s fault, the event as the soak
    writes one (kind, start, end, bound): its robots that stop (a burst, ``overload``: from
    the first of them to start until the last stops), else its first server hang (the
    soak's ``server_stop``); ValueError when it has neither."""
    robots = scenario.of_role('robot')
    fleet = [h.id for h in robots if h.stop is None and h.start == 0]
    bursting = [h for h in robots if h.stop is not None]
    if bursting:
        return {'kind': 'overload', 'start': min(h.start for h in bursting),
                'end': max(h.stop for h in bursting), 'bound': RECOVERY}, fleet
    hangs = sorted(span for h in scenario.of_role('server') for span in h.hang)
    if not hangs:
        raise ValueError('%s: no robot stops and no server hangs, so there is no fault to '
                         'recover from' % scenario.source)
    return {'kind': 'server_stop', 'start': hangs[0][0], 'end': hangs[0][1],
            'bound': RECOVERY}, fleet


def reports(sim, timeout):
    """The run's task reports as the soak reads them (sent at ``t``; a failed task's round
    trip is the timeout)."""
    return sorted((Task(r.outcome.stamp, r.robot, r.outcome.kind, r.outcome.ok,
                        r.outcome.rtt if r.outcome.ok else timeout) for r in sim.records),
                  key=lambda task: task.t)


def recovery(scenario, model, seed, variant):
    """s from the end of ``scenario``'s fault until ``variant``'s fleet is back (None: not
    within LIMIT s) with ``seed``."""
    event, fleet = fault_of(scenario)
    sim = simulate(scenario, model, seed, [variant])
    back, _ = checks.recovery(reports(sim, sim.timeout), event, [event], set(fleet),
                              event['end'] + LIMIT)
    return back


def times_of(scenario, model, variants, seeds):
    """``{variant: [s back after the burst per seed 1..seeds, None: not within LIMIT]}``."""
    return dict((variant, [recovery(scenario, model, seed, variant)
                           for seed in range(1, seeds + 1)]) for variant in variants)


def row(name, found, base=None):
    """A table row of one variant's per-seed times (None: not back within LIMIT s, counted
    at LIMIT), and its paired difference from ``base`` (over the seeds both have) when
    given."""
    times = [LIMIT if t is None else t for t in found]
    ninth = statistics.quantiles(times, n=10)[-1] if len(times) > 1 else times[0]
    cells = ['%.1f' % statistics.median(times), '%.1f' % ninth,
             '%.1f%s' % (max(times), '+' if None in found else ''),
             '%d of %d' % (sum(1 for t in times if t > RECOVERY), len(times))]
    if base is None:
        return '| %s | %s | | |' % (name, ' | '.join(cells))
    before = [LIMIT if t is None else t for t in base]
    mean, low, high = paired(times, before)
    sooner = sum(1 for a, b in zip(times, before) if a < b - 0.05)
    later = sum(1 for a, b in zip(times, before) if a > b + 0.05)
    return '| %s | %s | %+.2f [%+.2f, %+.2f] | %d / %d |' % (
        name, ' | '.join(cells), mean, low, high, sooner, later)


def table(found, against=None):
    """The markdown table of ``found`` (:func:`times_of`): each variant after the first
    against the first, and each against the same variant of ``against`` when given."""
    names = list(found)
    lines = ['| variant | median | p90 | max | over the bound | minus the base, s (95 %) | '
             'seeds sooner / later |', '|---|---|---|---|---|---|---|']
    for i, name in enumerate(names):
        lines.append(row(name, found[name], found[names[0]] if i else None))
        if against and name in against:
            lines.append(row('%s minus the kept run' % name, found[name], against[name]))
    return '\n'.join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(prog='recovery', description=__doc__.split('\n\n')[0])
    parser.add_argument('scenario', help='a scenario file whose burst robots stop, or one '
                        'of whose servers hangs')
    parser.add_argument('--variants', default='fleet,prequal,oracle_fleet')
    parser.add_argument('--seeds', type=int, default=40)
    parser.add_argument('--out', metavar='FILE', help='write the per-seed times (JSON)')
    parser.add_argument('--against', metavar='FILE', help='a kept run (--out) to pair with')
    args = parser.parse_args(argv)
    against = None
    if args.against:
        with open(args.against) as stream:
            against = json.load(stream)
    scenario, model = Scenario.load(args.scenario), Model.load()
    found = times_of(scenario, model, args.variants.split(','), args.seeds)
    print('recovery after the %s (s; the soak bound %g s), %d seeds; base: %s'
          % (fault_of(scenario)[0]['kind'], RECOVERY, args.seeds, args.variants.split(',')[0]))
    print(table(found, against))
    if args.out:
        with open(args.out, 'w') as stream:
            json.dump(found, stream)
    return 0


if __name__ == '__main__':
    sys.exit(main())
