"""Bytes on the wire per task: broadcast (paper) vs direct (fleet) routing (testbed, root).

Two robots send tasks to server 1 (``mode:=fixed``) while 2, 4 or 8 servers run, each host
in a network namespace of its own behind the link emulator, which counts every byte; the
two layouts run at once, each in a testbed of its own (bytes do not depend on timing). With
``routing:=broadcast`` each task goes to every server and each result to every robot;
with ``direct`` a task goes to the addressed server only and a result to its robot only.
Printed per layout, task kind and number of servers: tasks answered by robot 1, and the
bytes per task on robot 1's links (sum over its links to every server) in each direction
(its one probe per server per second is included: about 0.2 kB per server and second).
"""

import sys
import tempfile

from server_select.bench import cli
from server_select.bench.harness import link_bytes, scenario_run
from server_select.ros.paths import package_file
from server_select.core.util.tables import markdown_table
from server_select.testbed import bag_analysis
from server_select.testbed.runner import at_once

KINDS = {
    'sort': ['task_rate:=2'],
    'frame': ['sort_tasks:=false', 'frame_rate:=1', 'image_transport:=raw',
              'image_source:=search:%s' % package_file('config', 'search_area.yaml')],
}


def scenario(servers, seconds):
    hosts = {'manager': {'role': 'manager'}}
    hosts.update(('server%d' % s, {'role': 'server', 'id': s}) for s in range(1, servers + 1))
    hosts.update(('robot%d' % r, {'role': 'robot', 'id': r}) for r in (1, 2))
    return {'name': 'routing', 'duration': seconds + 12, 'hosts': hosts,
            'default': {'delay': 0.5}, 'links': {}}


def run_once(routing, kind, servers, seconds, work):
    data = scenario(servers, seconds)
    name = '%s-%s-%d' % (routing, kind, servers)
    ids = ','.join(str(s) for s in range(1, servers + 1))
    with scenario_run(data, work, name, 'ssrb-' + routing[0]) as (run, bag):
        for server in range(1, servers + 1):
            run.launch('server%d' % server, 'server.launch', 'server_id:=%d' % server,
                       'routing:=%s' % routing)
        for robot in (1, 2):
            run.launch('robot%d' % robot, 'robot.launch', 'robot_id:=%d' % robot,
                       'servers:=%s' % ids, 'mode:=fixed', 'fixed_server:=1',
                       'routing:=%s' % routing, 'start_delay:=2', *KINDS[kind], stage=0)
    link = link_bytes(work, name)
    reports = [r for r in bag_analysis.load(bag).reports if r.robot == 1]
    up = sum(v['bytes'] for k, v in link.items() if k.startswith('robot1>'))
    down = sum(v['bytes'] for k, v in link.items() if k.endswith('>robot1'))
    return {'routing': routing, 'kind': kind, 'servers': servers, 'tasks': len(reports),
            'ok': sum(1 for r in reports if r.ok), 'up_kb': up / 1e3 / max(1, len(reports)),
            'down_kb': down / 1e3 / max(1, len(reports))}


def table(rows):
    return markdown_table(
        ('routing', 'task', 'servers', 'tasks of robot 1 (ok)', 'kB/task robot 1 -> servers',
         'kB/task servers -> robot 1'),
        [(r['routing'], r['kind'], r['servers'], '%d (%d)' % (r['tasks'], r['ok']),
          '%.1f' % r['up_kb'], '%.1f' % r['down_kb']) for r in rows])


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--servers', default='2,4,8')
    parser.add_argument('--kinds', default='sort,frame')
    parser.add_argument('--seconds', type=float, default=20.0, help='tasks sent per run')
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory(prefix='bench_routing') as work:
        for kind in args.kinds.split(','):
            for servers in map(int, args.servers.split(',')):   # the two at once
                rows += at_once([(run_once, (routing, kind, servers, args.seconds, work))
                                 for routing in ('broadcast', 'direct')])
                print('\n'.join(table(rows[-2:]).splitlines()[-2:]), file=sys.stderr,
                      flush=True)
    cli.write(args.out, 'routing_bytes.json', rows)
    print('\nTwo robots, tasks to server 1; bytes counted by the link emulator\n\n%s\n'
          % table(rows))
    return 0


if __name__ == '__main__':
    sys.exit(main())
