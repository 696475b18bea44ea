"""Scenarios nobody wrote (no rospy): a seeded generator of scenario files in the testbed's
format, so a rule is judged on hundreds of fields and not on the few it was tuned on.

Each seed draws a field: 1-4 robots and 2-6 servers; per pair a one-way delay (1-20 ms),
jitter, sometimes loss; events after the first 15 s: ramps (a robot moving), steps,
outages of 1-15 s; servers that hang, come up late, stop, or get slower for a while;
CPU shares on some servers; the robots' tasks (sort tasks at 1-5 a second, or camera
frames at a share of what the servers can do). The same seed gives the same file.

``python3 -m server_select.sim.generate --count 200 --first-seed 1 --out DIR`` writes
``gen<seed>.yaml`` files; the league takes ``gen:<seed>`` as a scenario name
(:func:`scenario`), or a range ``gen:1-200``.
"""

import argparse
import os
import random
import sys

import yaml

from server_select.testbed.scenario import Scenario

MEASURE_FROM = 10.0          # s: the robots are up
FRAME_CPU = 0.13             # s of CPU per frame (config/sim/model.yaml): the offered load


def _link_events(rng, duration):
    delay = round(rng.uniform(1.0, 20.0), 2)
    first = {'at': 0, 'delay': delay, 'jitter': round(rng.choice([0.1, 0.3, 0.5, 1.0, 2.0]), 2)}
    if rng.random() < 0.15:
        first['loss'] = rng.choice([0.005, 0.01, 0.02])
    events, t = [first], 15.0
    while t < duration - 10.0:
        t += rng.uniform(5.0, 40.0)
        if t >= duration - 5.0:
            break
        roll = rng.random()
        if roll < 0.35:
            over = round(rng.uniform(5.0, 40.0), 1)
            events.append({'at': round(t, 1), 'ramp': round(rng.uniform(1.0, 25.0), 2),
                           'over': over})
            t += over
        elif roll < 0.55:
            events.append({'at': round(t, 1), 'delay': round(rng.uniform(1.0, 25.0), 2)})
        elif roll < 0.7:
            events.append({'at': round(t, 1), 'down': True})
            t += rng.uniform(1.0, 15.0)
            events.append({'at': round(t, 1), 'down': False})
    return events


def _server(rng, ident, duration, frames):
    spec = {'role': 'server', 'id': ident}
    if frames or rng.random() < 0.2:
        spec['cpu'] = round(rng.choice([0.1, 0.15, 0.2, 0.25, 0.4, 0.5, 1.0]), 2)
    roll = rng.random()
    if roll < 0.1:
        a = round(rng.uniform(20.0, duration - 20.0), 1)
        spec['hang'] = [[a, round(a + rng.uniform(3.0, 15.0), 1)]]
    elif roll < 0.2:
        spec['start'] = round(rng.uniform(15.0, duration / 2.0), 1)
    elif roll < 0.25:
        spec['stop'] = round(rng.uniform(duration / 2.0, duration - 5.0), 1)
    elif roll < 0.4:
        a = round(rng.uniform(15.0, duration - 20.0), 1)
        spec['work'] = [{'at': a, 'delay': round(rng.uniform(5.0, 40.0), 1)},
                        {'at': round(a + rng.uniform(10.0, 40.0), 1), 'delay': 0}]
    return spec


def generated(seed):
    """The scenario mapping of ``seed``."""
    rng = random.Random('generate/%s' % seed)
    robots, servers = rng.randint(1, 4), rng.randint(2, 6)
    duration = float(rng.choice([60, 90, 120]))
    frames = rng.random() < 0.2
    hosts = {'manager': {'role': 'manager'}}
    for s in range(1, servers + 1):
        hosts['server%d' % s] = _server(rng, s, duration, frames)
    if all('start' in h or 'stop' in h for name, h in hosts.items() if name != 'manager'):
        hosts['server1'].pop('start', None)        # one server is up throughout
        hosts['server1'].pop('stop', None)
    links = {}
    for r in range(1, robots + 1):
        hosts['robot%d' % r] = {'role': 'robot', 'id': r}
        for s in range(1, servers + 1):
            links['robot%d server%d' % (r, s)] = _link_events(rng, duration)
    if frames:
        capacity = sum(h.get('cpu', 1.0) for h in hosts.values() if h['role'] == 'server') \
            / FRAME_CPU
        args = {'sort_tasks': False, 'image_source': 'frames', 'task_timeout': 5,
                'frame_rate': round(rng.uniform(0.3, 1.2) * capacity / robots, 3)}
    else:
        args = {'task_rate': rng.choice([1, 2, 2, 4, 5])}
    return {'name': 'gen%d' % seed, 'duration': duration, 'hosts': hosts,
            'default': {'delay': 10, 'jitter': 0.3}, 'links': links,
            'suite': {'robot_args': args, 'measure_from': MEASURE_FROM}}


def scenario(name):
    """The Scenario of ``gen:<seed>``."""
    return Scenario(generated(int(name.split(':', 1)[1])), name)


def expand(names):
    """``names`` with each ``gen:a-b`` replaced by ``gen:a`` ... ``gen:b``."""
    result = []
    for name in names:
        if name.startswith('gen:') and '-' in name:
            first, last = name[4:].split('-')
            result.extend('gen:%d' % s for s in range(int(first), int(last) + 1))
        else:
            result.append(name)
    return result


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--count', type=int, default=10)
    parser.add_argument('--first-seed', type=int, default=1)
    parser.add_argument('--out', required=True)
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    for seed in range(args.first_seed, args.first_seed + args.count):
        data = generated(seed)
        Scenario(data, 'gen%d' % seed)          # a file the testbed can read
        path = os.path.join(args.out, 'gen%d.yaml' % seed)
        with open(path, 'w') as stream:
            stream.write('# python3 -m server_select.sim.generate --first-seed %d --count 1\n'
                         % seed)
            yaml.safe_dump(data, stream, sort_keys=False)
    print('%d scenarios in %s' % (args.count, args.out))
    return 0


if __name__ == '__main__':
    sys.exit(main())
