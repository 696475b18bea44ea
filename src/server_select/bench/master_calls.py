"""Calls to the ROS master per node in steady state (make bench-master).

A real roscore, and between it and every node a counting XML-RPC proxy: the nodes are
given the proxy's address as ``ROS_MASTER_URI``, and the proxy forwards each call to the
master and counts it by method and caller. The demo fleet (manager, servers, robots on
this host) runs in each profile; after a warm-up the calls of ``--seconds`` s are counted.
Printed: calls per second in all and per node, by method and by role (manager, robot,
server), each profile side by side, and what that comes to for a fleet of 1,000 robots
and 1,000 servers at the measured rates of each role.
"""

import collections
import http.client
import http.server
import json
import os
import sys
import tempfile
import threading
import time
import xmlrpc.client

import rosgraph

from server_select.bench import cli
from server_select.bench.harness import Roscore, launched
from server_select.core.config import names
from server_select.core.util.procs import wait_until
from server_select.core.util.tables import markdown_table


class CountingProxy(object):
    """An HTTP server on a free port of this host that forwards every XML-RPC call to
    ``master`` (``host, port``) and counts it: ``counts[(method, caller)]``."""

    def __init__(self, master):
        self.master = master
        self.lock = threading.Lock()
        self.counts = collections.Counter()
        proxy = self

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_POST(self):
                body = self.rfile.read(int(self.headers.get('Content-Length', 0)))
                try:
                    params, method = xmlrpc.client.loads(body)
                    caller = params[0] if params and isinstance(params[0], str) else '?'
                except Exception:        # not XML-RPC: forwarded all the same
                    method, caller = '?', '?'
                with proxy.lock:
                    proxy.counts[(method, caller)] += 1
                conn = http.client.HTTPConnection(*proxy.master, timeout=30)
                try:
                    conn.request('POST', self.path, body, {'Content-Type': 'text/xml'})
                    answer = conn.getresponse()
                    data = answer.read()
                    status = answer.status
                finally:
                    conn.close()
                self.send_response(status)
                self.send_header('Content-Type', 'text/xml')
                self.send_header('Content-Length', str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            def log_message(self, *args):
                pass

        self.server = http.server.ThreadingHTTPServer(('127.0.0.1', 0), Handler)
        self.server.daemon_threads = True
        self.port = self.server.server_address[1]
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def take(self):
        """The counts since the last take (and start afresh)."""
        with self.lock:
            counts, self.counts = self.counts, collections.Counter()
        return counts

    def close(self):
        self.server.shutdown()
        self.server.server_close()


def started(master, nodes):
    """Whether every one of ``nodes`` has finished starting: its last step is to publish
    (the manager) or hear ``/master_pid`` (every other node), so until then a node's
    start-up calls would count as steady state."""
    try:
        publishers, subscribers, _ = master.getSystemState()
    except (rosgraph.MasterError, OSError):
        return False
    on_topic = set()
    for topic, members in publishers + subscribers:
        if topic == '/' + names.MASTER_PID_TOPIC:
            on_topic.update(members)
    return set(nodes) <= on_topic


def measure(profile, robots, servers, warmup, seconds, work):
    """Calls by method and caller during ``seconds`` of the demo fleet in ``profile``."""
    with Roscore(work) as core:
        proxy = CountingProxy(('127.0.0.1', core.port))
        fleet_nodes = ['/manager'] + ['/server%d' % s for s in range(1, servers + 1)] + \
            ['/robot%d' % r for r in range(1, robots + 1)]
        args = ['output:=log', 'profile:=%s' % profile, 'n_robots:=%d' % robots,
                'n_servers:=%d' % servers]
        try:
            with launched('demo.launch', args, os.path.join(work, 'fleet_%s.log' % profile),
                          'http://127.0.0.1:%d' % proxy.port, fleet_nodes, 120.0,
                          env={'ROS_HOME': os.path.join(work, 'ros_home_%s' % profile)}):
                master = rosgraph.Master('/bench_master', master_uri=core.uri)
                if not wait_until(lambda: started(master, fleet_nodes), 120.0, period=0.5):
                    raise RuntimeError('the fleet did not come up (see %s)' % work)
                time.sleep(warmup)          # then its first look-ups settle
                proxy.take()
                time.sleep(seconds)
                counts = proxy.take()
        finally:
            proxy.close()
    return {'profile': profile, 'robots': robots, 'servers': servers, 'seconds': seconds,
            'nodes': fleet_nodes,
            'calls': [{'method': m, 'caller': c, 'count': n}
                      for (m, c), n in sorted(counts.items())]}


def rates(run):
    """``(calls/s in all, per node, {method: calls/s}, {role: calls/s per node})`` of the
    fleet's nodes (roles: manager, robot, server)."""
    fleet = set(run['nodes'])
    by_method, by_role = collections.Counter(), collections.Counter()
    for row in run['calls']:
        if row['caller'] in fleet:
            by_method[row['method']] += row['count'] / run['seconds']
            by_role[row['caller'].strip('/').rstrip('0123456789')] += \
                row['count'] / run['seconds']
    counts = {'manager': 1, 'robot': run['robots'], 'server': run['servers']}
    per_role = dict((role, by_role[role] / n) for role, n in counts.items())
    total = sum(by_method.values())
    return total, total / max(1, len(fleet)), by_method, per_role


def at_scale(per_role, robots=1000, servers=1000):
    """Calls/s of a fleet of ``robots`` and ``servers`` at the measured rates per node."""
    return per_role['manager'] + robots * per_role['robot'] + servers * per_role['server']


def table(runs):
    methods = sorted(set(m for run in runs for m in rates(run)[2]))
    rows = []
    for run in runs:
        total, per_node, by_method, per_role = rates(run)
        rows.append([run['profile'], '%d + %d + 1' % (run['robots'], run['servers']),
                     '%.2f' % total, '%.3f' % per_node,
                     '%.3f / %.3f / %.3f' % (per_role['manager'], per_role['robot'],
                                             per_role['server']),
                     '%.0f (%.3f)' % (at_scale(per_role), at_scale(per_role) / 2001)] +
                    ['%.2f' % by_method.get(m, 0.0) for m in methods])
    return markdown_table(['profile', 'robots + servers + manager', 'calls/s', 'per node',
                           'per manager / robot / server', 'at 1,000 + 1,000 + 1 (per node)']
                          + methods, rows)


def render(paths):
    """The table of earlier runs' JSON files (``--render``)."""
    runs = []
    for path in paths:
        with open(path) as stream:
            runs += json.load(stream)
    return table(runs)


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--robots', type=int, default=20)
    parser.add_argument('--servers', type=int, default=5)
    parser.add_argument('--warmup', type=float, default=10.0,
                        help='s after every node registered, before counting')
    parser.add_argument('--seconds', type=float, default=60.0, help='s counted')
    parser.add_argument('--profiles', default='paper,fleet')
    parser.add_argument('--render', nargs='*', help='only print the table of these JSON files')
    args = parser.parse_args(argv)
    if args.render:
        print(render(args.render))
        return 0
    runs = []
    with tempfile.TemporaryDirectory(prefix='bench_master') as work:
        for profile in args.profiles.split(','):
            runs.append(measure(profile, args.robots, args.servers, args.warmup, args.seconds,
                                work))
            print(table(runs[-1:]).splitlines()[-1], file=sys.stderr, flush=True)
    cli.write(args.out, 'master_calls.json', runs)
    text = table(runs)
    cli.write(args.out, 'master_calls.md', '# Master calls in steady state\n\n' + text + '\n')
    print('\nCalls to the master per second in steady state, demo fleet on one host '
          '(%g s counted after %g s)\n\n%s\n' % (args.seconds, args.warmup, text))
    return 0


if __name__ == '__main__':
    sys.exit(main())
