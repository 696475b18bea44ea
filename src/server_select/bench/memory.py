"""Memory of every node of the demo fleet over a long run: does anything grow without bound?

Starts a roscore of its own and ``demo.launch`` (3 servers, 2 robots) with sort tasks at
``--rate`` per robot, then samples each node's RSS every ``--every`` s for ``--minutes``
and prints one Markdown table (RSS MiB per node per sample time) with the growth from the
first sample after warm-up to the last. Nothing is asserted.
"""

import os
import sys
import tempfile
import time

import psutil

from server_select.bench import cli
from server_select.bench.harness import Roscore, launched
from server_select.core.util.tables import markdown_table

NODES = ('/manager', '/server1', '/server2', '/server3', '/robot1', '/robot2')


def sample(by_node):
    rss = {}
    for node, pid in by_node.items():
        try:
            rss[node] = psutil.Process(pid).memory_info().rss / 2.0 ** 20
        except psutil.Error:
            rss[node] = None
    return rss


def run(minutes, rate, every, log):
    with tempfile.TemporaryDirectory(prefix='bench_memory') as tmp, Roscore(tmp), \
            launched('demo.launch', ['task_rate:=%g' % rate, 'output:=log'], log,
                     nodes=NODES) as by_node:
        start, rows = time.monotonic(), []
        while time.monotonic() - start < minutes * 60:
            time.sleep(min(every, max(0.0, minutes * 60 - (time.monotonic() - start))))
            rows.append((time.monotonic() - start, sample(by_node)))
            print('memory: %.0f s' % rows[-1][0], file=sys.stderr, flush=True)
    return rows


def table(rows):
    def mib(value):
        return '%.1f' % value if value is not None else 'exited'
    first, last = rows[0][1], rows[-1][1]
    growth = ['%+.1f' % (last[n] - first[n]) if None not in (first[n], last[n]) else '-'
              for n in NODES]
    return markdown_table(['after s'] + list(NODES),
                          [['%.0f' % t] + [mib(rss[n]) for n in NODES] for t, rss in rows]
                          + [['growth'] + growth])


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--minutes', type=float, default=10.0)
    parser.add_argument('--rate', type=float, default=20.0, help='sort tasks/s per robot')
    parser.add_argument('--every', type=float, default=60.0, help='seconds between samples')
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    rows = run(args.minutes, args.rate, args.every, os.path.join(args.out, 'memory_nodes.log'))
    cli.write(args.out, 'memory.json', [{'t': t, 'rss_mb': rss} for t, rss in rows])
    text = table(rows)
    print('\nRSS MiB of every node, sort tasks at %g/s per robot\n\n%s\n' % (args.rate, text))
    return 0


if __name__ == '__main__':
    sys.exit(main())
