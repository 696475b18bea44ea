"""Cost of signed fleet messages (``~fleet_key``): microseconds to seal and to check one
message, beside what serializing it once costs anyway, at the fleet's message sizes.

For each message (a flag ranking 3 and 100 servers, a robot's probe batch of 10 and 100
servers, a sort result of 1000 and 20000 values, an image result with a 50 kB JPEG or a raw
640x480 frame), ``--repeats`` runs of
``--count`` seals and checks each; printed: the median and spread over the runs of us per
seal, us per check, and us per plain serialization (what rospy spends publishing it
unsigned), and their ratio. No master, no node: the functions the nodes call
(:func:`server_select.ros.seal.sealed` and :func:`~server_select.ros.seal.check`).
"""

import io
import statistics
import sys
import time

import numpy as np
from rospy.numpy_msg import numpy_msg

from server_select.bench import cli
from server_select.core.trust.keys import KEY_BYTES, Keys
from server_select.core.trust.seal import Sealer, Verifier, publisher_role
from server_select.core.util.tables import markdown_table
from server_select.msg import ImageResult, LatencySamples, SelectionFlag, SortResult
from server_select.ros.seal import check, sealed


def messages():
    """(name, a function making a fresh message) for each size measured."""
    def flag(n):
        return lambda: SelectionFlag(robot_id=1, server_id=1, ranking=list(range(1, n + 1)),
                                     mean_latency=[1e-3] * n, sample_count=[6] * n)

    def batch(n):
        return lambda: LatencySamples(robot_id=1, server_id=list(range(1, n + 1)),
                                      ok=[True] * n, rtt=[1e-3] * n)

    def sort(n):
        data = np.arange(n, dtype=np.int32)
        return lambda: numpy_msg(SortResult)(robot_id=1, task_id=1, server_id=1, ok=True,
                                             data=data)

    def jpeg():        # the annotated frame of a compressed task, as JPEG
        msg = ImageResult(robot_id=1, task_id=1, server_id=1, ok=True, detection_count=1)
        msg.compressed.format, msg.compressed.data = 'jpeg', bytes(50000)
        return msg

    def raw():         # ... of a raw 640x480 task, bgr8
        msg = ImageResult(robot_id=1, task_id=1, server_id=1, ok=True, detection_count=1)
        msg.image.height, msg.image.width, msg.image.encoding = 480, 640, 'bgr8'
        msg.image.step, msg.image.data = 640 * 3, bytes(640 * 480 * 3)
        return msg
    return [('flag, 3 servers', flag(3)), ('flag, 100 servers', flag(100)),
            ('probe batch, 10 servers', batch(10)), ('probe batch, 100 servers', batch(100)),
            ('sort result, 1000 values', sort(1000)), ('sort result, 20000 values', sort(20000)),
            ('image result, 50 kB JPEG', jpeg), ('image result, 640x480 bgr8', raw)]


def per_message_us(fn, count):
    start = time.perf_counter()
    for _ in range(count):
        fn()
    return (time.perf_counter() - start) / count * 1e6


TOPIC = '/bench_topic'     # what a seal binds a message to (any name measures the same)


def measure(make, count):
    """us per plain serialization, per seal, per check (one run)."""
    msg = make()
    keys = Keys.from_fleet(b'k' * KEY_BYTES, publisher_role(msg._type))
    sealer, verifier = Sealer(keys, '/manager'), Verifier([keys], max_age=3600.0)
    plain = per_message_us(lambda: msg.serialize(io.BytesIO()), count)
    seal_us = per_message_us(lambda: sealed(msg, sealer, TOPIC), count)
    copies = [sealed(make(), sealer, TOPIC) for _ in range(count)]   # each seen once
    it = iter(copies)
    check_us = per_message_us(lambda: check(next(it), '/manager', verifier, TOPIC), count)
    assert check(sealed(make(), sealer, TOPIC), '/manager', verifier, TOPIC) is None
    return plain, seal_us, check_us


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--count', type=int, default=2000, help='messages per run')
    parser.add_argument('--repeats', type=int, default=5)
    args = parser.parse_args(argv)
    rows, body = [], []
    for name, make in messages():
        runs = [measure(make, args.count) for _ in range(args.repeats)]
        figures = dict((what, [r[i] for r in runs])
                       for i, what in enumerate(('serialize_us', 'seal_us', 'check_us')))
        row = dict(message=name, **figures)
        rows.append(row)
        med = dict((k, statistics.median(v)) for k, v in figures.items())
        body.append([name] + ['%.1f (%.1f-%.1f)' % (med[k], min(figures[k]), max(figures[k]))
                              for k in ('serialize_us', 'seal_us', 'check_us')] +
                    ['%.1f' % ((med['seal_us'] + med['check_us']) / med['serialize_us'])])
        print('%s done' % name, file=sys.stderr, flush=True)
    text = markdown_table(['message', 'serialize us', 'seal us', 'check us',
                           '(seal + check) / serialize'], body)
    cli.write(args.out, 'seal_cost.json', rows)
    cli.write(args.out, 'seal_cost.md', text + '\n')
    print('us per message, median (min-max) of %d runs of %d:\n%s'
          % (args.repeats, args.count, text))
    return 0


if __name__ == '__main__':
    sys.exit(main())
