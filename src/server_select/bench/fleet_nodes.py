"""A fleet of real nodes on one host: what each role costs (make bench-fleet).

For each size R x S: a roscore of its own and ``demo.launch profile:=fleet`` with R robot
and S server processes and the manager (sort tasks at ``--task-rate``), in two layouts side
by side: ``samples`` (every probe sample to the manager, every flag on the shared topic:
the fleet profile before robots ranked for themselves) and ``views`` (the fleet profile:
robots send their own rankings, each flag goes to its robot alone). Once every robot has
a flag, for ``--seconds`` s: CPU (% of one core) and RSS of every process by role, and the
bytes on the manager's inputs and on each robot's flag connection (the bench hears the
shared flag topic, which the manager also writes while a recorder listens: a robot on
the shared topic receives every flag there, a robot on its own topic its own). The last
rows scale the measured per-node rates to 1,000 robots (the flag sizes as measured, for
S servers). Nothing is asserted.
"""

import os
import struct
import sys
import tempfile
import threading
import time

import rospy

from server_select.bench import cli
from server_select.bench.harness import Roscore, launched
from server_select.core.config import names
from server_select.core.util.procs import measure, wait_until
from server_select.core.util.tables import fmt, markdown_table

LAYOUTS = {'samples': ['sample_stream:=robot', 'flag_stream:=shared'], 'views': []}
INPUTS = {'samples': (names.SAMPLES_TOPIC, names.TASK_SAMPLES_TOPIC),
          'views': (names.RANKINGS_TOPIC,)}


class Counter(object):
    """Messages and bytes heard on topics, by topic, and the robots flagged so far."""

    def __init__(self, topics):
        self.lock = threading.Lock()
        self.counts = dict((t, [0, 0]) for t in topics)
        self.flagged = set()
        self.subs = [rospy.Subscriber('/' + t, rospy.AnyMsg, self.on_msg, t,
                                      queue_size=10000) for t in topics]

    def on_msg(self, msg, topic):
        with self.lock:
            count = self.counts[topic]
            count[0] += 1
            count[1] += len(msg._buff) + 4          # + TCPROS's length prefix
            if topic == names.SELECTION_TOPIC:      # robot_id: after the header
                self.flagged.add(_robot_of_flag(msg._buff))

    def take(self):
        with self.lock:
            taken = dict((t, tuple(c)) for t, c in self.counts.items())
            for count in self.counts.values():
                count[0] = count[1] = 0
            return taken

    def close(self):
        for sub in self.subs:
            sub.unregister()


def _robot_of_flag(buff):
    """The robot_id of a serialized SelectionFlag (uint32 after the header)."""
    frame_len = struct.unpack_from('<I', buff, 12)[0]     # after seq, secs, nsecs
    return struct.unpack_from('<I', buff, 16 + frame_len)[0]


def run_one(robots, servers, layout, seconds, task_rate, work):
    """One size and layout under the running roscore: the row of figures."""
    args = ['output:=log', 'profile:=fleet', 'n_robots:=%d' % robots,
            'n_servers:=%d' % servers, 'task_rate:=%g' % task_rate] + LAYOUTS[layout]
    nodes = dict([('/manager', 'manager')] + [('/robot%d' % r, 'robot')
                                              for r in range(1, robots + 1)] +
                 [('/server%d' % s, 'server') for s in range(1, servers + 1)])
    counter = Counter((names.SELECTION_TOPIC,) + INPUTS[layout])
    log = os.path.join(work, 'fleet_%s_%dx%d.log' % (layout, robots, servers))
    try:
        with launched('demo.launch', args, log, nodes=list(nodes),
                      timeout=60.0 + 2.0 * robots) as by_node:
            up = wait_until(lambda: len(counter.flagged) >= robots, 60.0 + 2.0 * robots,
                            period=0.5)
            pids = dict((pid, nodes[node]) for node, pid in by_node.items())
            time.sleep(5.0)                 # a few flags each, then counted
            counter.take()
            began = time.monotonic()
            usage = measure(list(pids), seconds)
            heard, span = counter.take(), time.monotonic() - began
    finally:
        counter.close()
    row = {'robots': robots, 'servers': servers, 'layout': layout, 'all_flagged': up,
           'seconds': span}
    for role in ('manager', 'robot', 'server'):
        used = [u for pid, u in usage.items() if pids[pid] == role]
        row[role + '_cpu'] = sum(u['cpu_percent'] for u in used) / max(1, len(used))
        row[role + '_rss'] = sum(u['rss_mb'] for u in used) / max(1, len(used))
        row[role + '_processes'] = len(used)
    flags, flag_bytes = heard[names.SELECTION_TOPIC]
    row['flag_size'] = flag_bytes / max(1, flags)
    # a robot on the shared topic gets every flag; on its own topic, its own
    row['flag_bytes_per_robot_s'] = flag_bytes / span / (1 if layout == 'samples' else robots)
    row['manager_in_bytes_s'] = sum(heard[t][1] for t in INPUTS[layout]) / span
    row['manager_in_msgs_s'] = sum(heard[t][0] for t in INPUTS[layout]) / span
    return row


def at_thousand(row, robots=1000):
    """The row's per-robot rates for ``robots`` robots: (manager input B/s, flag B/s to a
    robot: every robot's flags on the shared topic, its own on its own)."""
    shared = row['layout'] == 'samples'
    own_flags = row['flag_bytes_per_robot_s'] / (row['robots'] if shared else 1)
    return (row['manager_in_bytes_s'] / row['robots'] * robots,
            own_flags * (robots if shared else 1))


def table(rows):
    header = ['robots x servers', 'layout', 'processes', 'manager CPU % / RSS MiB',
              'robot CPU % / RSS MiB (mean)', 'server CPU % / RSS MiB (mean)',
              'manager input msgs/s, kB/s', 'flag B/s to a robot',
              'at 1,000 robots: manager input kB/s, flag B/s to a robot']
    body = []
    for r in rows:
        big_in, big_flags = at_thousand(r)
        body.append(['%d x %d' % (r['robots'], r['servers']), r['layout'],
                     str(r['manager_processes'] + r['robot_processes'] + r['server_processes']),
                     '%s / %s' % (fmt(r['manager_cpu'], '%.1f'), fmt(r['manager_rss'], '%.0f')),
                     '%s / %s' % (fmt(r['robot_cpu'], '%.1f'), fmt(r['robot_rss'], '%.0f')),
                     '%s / %s' % (fmt(r['server_cpu'], '%.1f'), fmt(r['server_rss'], '%.0f')),
                     '%.0f, %.1f' % (r['manager_in_msgs_s'], r['manager_in_bytes_s'] / 1e3),
                     '%.0f' % r['flag_bytes_per_robot_s'],
                     '%.0f, %.0f' % (big_in / 1e3, big_flags)])
    return markdown_table(header, body)


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--sizes', default='10x5,30x10,60x15', help='RxS,...')
    parser.add_argument('--layouts', default='samples,views')
    parser.add_argument('--seconds', type=float, default=20.0)
    parser.add_argument('--task-rate', type=float, default=1.0)
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory(prefix='bench_fleet') as tmp, Roscore(tmp):
        rospy.init_node('bench_fleet', disable_signals=True)
        for size in args.sizes.split(','):
            robots, servers = map(int, size.lower().split('x'))
            for layout in args.layouts.split(','):
                print('fleet: %d x %d, %s' % (robots, servers, layout), file=sys.stderr,
                      flush=True)
                rows.append(run_one(robots, servers, layout, args.seconds, args.task_rate,
                                    tmp))
                print(table(rows[-1:]).splitlines()[-1], file=sys.stderr, flush=True)
        rospy.signal_shutdown('done')
    cli.write(args.out, 'fleet_nodes.json', rows)
    print(table(rows))


if __name__ == '__main__':
    main()
