"""What one decision of a fleet robot's rule costs (``python3 -m
server_select.bench.decision``): a task's ask (``order``) and its send (``started``), on a
``least_latency`` rule fed as the fleet profile feeds it (its contenders' probe answers at
4 Hz, the others' at 1 Hz, a 2 s window, each answer reporting a loaded server; a task
every 0.5 s), for 4 and 30 servers. Prints microseconds a decision, median (min-max) of
repeated runs, and writes ``decision.json``.
"""

import random
import sys
import time

from server_select.bench.cli import parser, write
from server_select.core.load.work_queue import Load
from server_select.core.peers.balancers import make
from server_select.core.settings import default
from server_select.core.util.tables import markdown_table, median_range

CONTENDERS = 3          # servers probed at the contenders' rate


class _Clock(object):
    now = 0.0

    def __call__(self):
        return self.now


class _Fleet(object):
    """A fleet robot's rule and what feeds it: ``servers``' probe answers as its plan sends
    them (its contenders at the contenders' rate, the others at the background rate)."""

    def __init__(self, servers, seed=1):
        self.clock, self.rng = _Clock(), random.Random(seed)
        self.servers = list(range(1, servers + 1))
        self.rule = make('least_latency', rng=random.Random(seed), clock=self.clock,
                         window=default('window', 'fleet'))
        self.step = 1.0 / default('contender_rate', 'fleet')
        self.ticks = 0
        self.feed(2 * default('window', 'fleet'))

    def feed(self, seconds):
        """Probe answers for ``seconds`` of the robot's life."""
        background = int(default('contender_rate', 'fleet') / default('background_rate',
                                                                      'fleet'))
        for _ in range(int(round(seconds / self.step))):
            self.clock.now += self.step
            self.ticks += 1
            for server in self.servers:
                if server <= CONTENDERS or self.ticks % background == server % background:
                    self.rule.probed(server, 0.001 * (1 + server % 7) +
                                     self.rng.uniform(0, 2e-4), Load(
                                         self.rng.randint(0, 2), self.rng.randint(0, 1), 2,
                                         0.002, {'sort': 0.003 + self.rng.uniform(0, 5e-4)},
                                         0.3))


def decisions(servers, count):
    """Seconds a decision (the ask and the send of a task) takes, over ``count`` tasks at
    the fleet's task rate (probes fed between them, not timed)."""
    fleet = _Fleet(servers)
    rule, period = fleet.rule, 1.0 / default('task_rate', 'fleet')
    spent = 0.0
    for _ in range(count):
        fleet.feed(period)
        start = time.perf_counter()
        order = rule.order(fleet.servers, 'sort')
        rule.started(order[0], 'sort', order=order)
        spent += time.perf_counter() - start
        rule.ended(order[0], 0.004)
    return spent / count


def main(argv=None):
    args_parser = parser(__doc__)
    args_parser.add_argument('--repeats', type=int, default=5)
    args_parser.add_argument('--count', type=int, default=2000, help='decisions a run')
    args = args_parser.parse_args(argv)
    rows, data = [], {}
    for servers in (4, 30):
        runs = [1e6 * decisions(servers, args.count) for _ in range(args.repeats)]
        data[servers] = runs
        rows.append([servers, median_range(runs)])
    print(markdown_table(['servers', 'us a decision, median (min-max) of %d runs'
                          % args.repeats], rows))
    write(args.out, 'decision.json', {'us_per_decision': data, 'count': args.count})
    return 0


if __name__ == '__main__':
    sys.exit(main())
