"""``make soak``: the keyed fleet on the testbed through a seeded schedule of faults, then
its invariants, recovery times and resource slopes checked from the bags (root, TUN).

    python -m server_select.soak.run --minutes 30 --seed 1 --out results/soak
    python -m server_select.soak.run --short --out /tmp/soak     # every kind once, in waves, ~2 min

Writes the bags, ``events.json`` (the nemesis's log), ``resources.csv``, ``report.md`` and
``timeline.png`` into ``--out``; exits 1 when an invariant fails.
"""

import argparse
import csv
import glob
import json
import os
import random
import sys
import time

from server_select.vision.image_source import write_frame
from server_select.core.trust.keys import make_key
from server_select.core.util.procs import wait_until
from server_select.soak import history, nemesis, plan, report
from server_select.soak.fleet import SoakFleet
from server_select.soak.report import TASK_TIMEOUT
from server_select.soak.resources import Sampler
from server_select.testbed.linkemu import EmulatorError
from server_select.testbed.netns import Testbed
from server_select.testbed.runner import MASTER_PORT, HostRun, guarded
from server_select.testbed.scenario import Scenario
from server_select.testbed.traces import own_prefix

EMULATOR = 'link emulator'   # sampled beside the nodes: it carries every packet
SETTLE = 10.0           # s after every node registered that failures count (first tasks)


def _keys(out, count):
    """``count`` new fleet key files in ``out``/keys: their absolute paths (the nodes that
    are given them start in ROS_HOME)."""
    folder = os.path.join(os.path.abspath(out), 'keys')
    os.makedirs(folder, exist_ok=True)
    paths = [os.path.join(folder, 'fleet_%d.key' % (n + 1)) for n in range(count)]
    for path in paths:
        if os.path.exists(path):
            os.remove(path)
        make_key(path)
    return paths


def _start_fleet(fleet, say):
    fleet.start('manager')
    for server in plan.SERVERS:
        fleet.start('server%d' % server)
    fleet.start_camera()
    for robot in plan.ROBOTS:
        fleet.start('robot%d' % robot)
    if not wait_until(lambda: all(fleet.pid(n) for n in nemesis.MAIN_NODES), 90.0, 0.5):
        raise EmulatorError('the fleet did not come up in 90 s: %s missing' % ', '.join(
            n for n in nemesis.MAIN_NODES if not fleet.pid(n)))
    say('fleet up: %s' % ', '.join(nemesis.MAIN_NODES))


def plan_of(args):
    """(s the soak lasts, its faults) from the command line's options (ValueError: the
    faults do not fit, or a kind is unknown)."""
    kinds = getattr(args, 'kinds', None) or tuple(plan.KINDS)
    duration = plan.needed(1, True, kinds) if args.short else args.minutes * 60.0
    return duration, plan.schedule(duration, random.Random(args.seed),
                                   1 if args.short else None, args.short, kinds)


def soak(args, say=print):
    """One soak; the folder's analysis (report.analyse's result)."""
    duration, faults = plan_of(args)
    rotations = sum(1 for f in faults if f.kind == 'key_rotation')
    # absolute: the nodes are handed paths in it (key files), and roslaunch starts them
    # in ROS_HOME, not here
    args.out = os.path.abspath(args.out)
    os.makedirs(args.out, exist_ok=True)
    for old in glob.glob(os.path.join(args.out, 'soak_*.bag*')):    # an earlier soak's
        os.remove(old)
    keys, frames = _keys(args.out, rotations + 2), os.path.join(args.out, 'frames')
    write_frame(frames)
    path = os.path.join(args.out, 'scenario.yaml')
    data = plan.scenario(faults, duration)
    with open(path, 'w') as stream:
        json.dump(data, stream)       # JSON is YAML
    say('soak: %.0f s, seed %d, %d faults: %s' % (duration, args.seed, len(faults), ', '.join(
        '%s@%.0f' % (f.kind, f.at) for f in faults)))
    run_dir = os.path.join(args.out, 'run')
    with Testbed(Scenario(data, path), path, run_dir, prefix=own_prefix('soak')) as tb:
        run = HostRun(tb, tb.scenario, run_dir)
        fleet = SoakFleet(run, keys, frames, args.out)
        cores = []

        def roscore():
            cores.append(run.popen('manager', ['roscore', '-p', str(MASTER_PORT)],
                                   'roscore_%d' % (len(cores) + 1), stage=3))
            if not wait_until(fleet.master.up, 30.0, period=0.3):
                raise EmulatorError('roscore did not come up within 30 s')
            return cores[-1]
        chaos = nemesis.Nemesis(fleet, tb, roscore, say)
        chaos.core = roscore()
        fleet.start_recorder()
        _start_fleet(fleet, say)
        run.start_clock()           # the faults' times count from here
        measured_from = time.time() + SETTLE
        emulator = tb.emulator.pid      # the testbed's own share of this host's CPU

        def pid_of(node):
            return emulator if node == EMULATOR else fleet.pid(node)
        sampler = Sampler(nemesis.MAIN_NODES + ['camera', EMULATOR], pid_of).start()
        try:
            chaos.run(faults)
            tb.sleep_until(max(duration, chaos.over + plan.TAIL[bool(args.short)]))
        finally:
            sampler.stop()
            measured = (measured_from, time.time() - TASK_TIMEOUT)
            fleet.close()
    _save(args.out, chaos, sampler, measured, tb.t0, duration)
    return report.analyse(args.out, history.load(args.out))


def _save(out, chaos, sampler, measured, t0, duration):
    with open(os.path.join(out, 'events.json'), 'w') as stream:
        json.dump({'t0': t0, 'duration': duration, 'measured': measured,
                   'events': chaos.events, 'stops': chaos.stops}, stream, indent=1)
    with open(os.path.join(out, 'resources.csv'), 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(sampler.samples[0]._fields if sampler.samples else ['t'])
        writer.writerows(sampler.samples)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--minutes', type=float, default=30.0, help='length (%(default)s)')
    parser.add_argument('--seed', type=int, default=1, help='the nemesis seed (%(default)s)')
    parser.add_argument('--short', action='store_true', help='every fault kind once, in waves')
    parser.add_argument('--kinds', type=lambda text: tuple(text.replace(',', ' ').split()),
                        help='only these fault kinds, e.g. overload,server_kill (as many '
                        'of each as fit)')
    parser.add_argument('--out', default='results/soak', help='folder (%(default)s)')
    args = parser.parse_args(argv)
    try:
        plan_of(args)
    except ValueError as error:
        parser.error(str(error))
    verdict = {}
    status = guarded('soak', lambda: verdict.update(soak(args)))
    if status:
        return status
    print(open(os.path.join(args.out, 'report.md')).read())
    return 0 if verdict.get('passed') else 1


if __name__ == '__main__':
    sys.exit(main())
