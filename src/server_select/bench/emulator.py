"""Emulator accuracy benchmark: configured round trip vs measured, on the testbed.

For each configured round trip (and a jitter case) a two-host testbed is brought up and
round trips are measured from host ``a`` to host ``b`` with a raw TCP socket echo and
with the LatencyProbe service (roscore on ``a``, a server node on ``b``). Prints a Markdown
table and writes JSON; it asserts nothing about timings.
"""

import json
import os
import sys
import tempfile
import time

import yaml

from server_select.bench import cli
from server_select.testbed.linkemu import EmulatorError
from server_select.testbed.scenario import Scenario
from server_select.core.util.stats import summarize
from server_select.core.util.tables import markdown_table
from server_select.testbed.netns import Testbed
from server_select.testbed.traces import own_prefix

CASES = [(1.0, 0.0), (5.0, 0.0), (20.0, 0.0), (100.0, 0.0), (20.0, 2.0)]


def tolerance_ms(rtt_ms):
    return max(0.05 * rtt_ms, 0.3)


def measure_case(rtt_ms, jitter_ms, work_dir, count, probe_count, prefix='ssbch'):
    data = {'name': 'emulator_bench', 'duration': 3600,
            'hosts': {'a': {'role': 'manager'}, 'b': {'role': 'server', 'id': 1}},
            'default': {'delay': rtt_ms / 2.0, 'jitter': jitter_ms / 2.0}}
    path = os.path.join(work_dir, 'bench_%g_%g.yaml' % (rtt_ms, jitter_ms))
    with open(path, 'w') as stream:
        yaml.safe_dump(data, stream)
    result = {'configured_rtt_ms': rtt_ms, 'configured_jitter_ms': jitter_ms}
    run_dir = os.path.join(work_dir, 'run')
    with Testbed(Scenario(data), path, run_dir, prefix=own_prefix(prefix)) as tb:
        py = [sys.executable, '-m', 'server_select.bench.netbench']
        tb.popen('b', py + ['echo-server', '--port', '5555'])
        out = tb.run('a', py + ['echo-client', '--host', tb.address('b'), '--port', '5555',
                                '--count', str(count),
                                '--interval', str(max(0.005, rtt_ms / 1000.0))], timeout=600)
        if out.returncode != 0:
            raise EmulatorError('echo client failed: %s' % out.stderr[-500:])
        result['socket'] = summarize(json.loads(out.stdout)['rtt'])
        env = dict(os.environ, ROS_MASTER_URI='http://%s:11311' % tb.address('a'))
        env.pop('ROS_HOSTNAME', None)
        env_a = dict(env, ROS_IP=tb.address('a'), ROS_HOME=os.path.join(work_dir, 'ros_a'))
        env_b = dict(env, ROS_IP=tb.address('b'), ROS_HOME=os.path.join(work_dir, 'ros_b'))
        tb.popen('a', ['roscore', '-p', '11311'], env=env_a, stage=2)
        tb.popen('b', ['roslaunch', '--wait', 'server_select', 'server.launch', 'server_id:=1',
                       'output:=log'], env=env_b)
        out = tb.run('a', py + ['probe-client', '--server-id', '1', '--count', str(probe_count)],
                     env=env_a, timeout=600)
        if out.returncode != 0:
            raise EmulatorError('probe client failed: %s' % out.stderr[-500:])
        probe = json.loads(out.stdout.strip().splitlines()[-1])
        result['probe'] = summarize(probe['rtt'])
        result['probe_failed'] = probe['failed']
    for key in ('socket', 'probe'):
        s = result[key]
        s['error_ms'] = s['mean'] * 1e3 - rtt_ms
        s['within_tolerance'] = abs(s['error_ms']) <= tolerance_ms(rtt_ms)
    return result


def table(results):
    rows = []
    for r in results:
        s, p = r['socket'], r['probe']
        jitter = r['configured_jitter_ms']
        rows.append(['%g (%s)' % (r['configured_rtt_ms'], '+-%g' % jitter if jitter else '-')]
                    + ['%.3f' % (x[k] * 1e3) for x in (s,) for k in ('mean', 'median', 'sd')]
                    + ['%+.3f' % s['error_ms']]
                    + ['%.3f' % (p[k] * 1e3) for k in ('mean', 'median', 'sd')]
                    + ['%+.3f' % p['error_ms'], '%.2f' % tolerance_ms(r['configured_rtt_ms']),
                       'yes' if s['within_tolerance'] else 'NO'])
    return markdown_table(
        ('configured RTT ms (jitter)', 'socket mean ms', 'median', 'sd', 'error ms',
         'probe mean ms', 'median', 'sd', 'error ms', 'tolerance ms', 'socket within'), rows)


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--count', type=int, default=300, help='socket round trips per case')
    parser.add_argument('--probe-count', type=int, default=100, help='probes per case')
    parser.add_argument('--cases', default='',
                        help='comma-separated RTT[:jitter] ms, default 1,5,20,100,20:2')
    args = parser.parse_args(argv)
    cases = CASES
    if args.cases:
        cases = [tuple(float(x) for x in (c.split(':') + ['0'])[:2]) for c in args.cases.split(',')]
    results = []
    with tempfile.TemporaryDirectory(prefix='emulator_bench') as work:
        try:
            for rtt, jitter in cases:
                started = time.monotonic()
                results.append(measure_case(rtt, jitter, work, args.count, args.probe_count))
                print('emulator_bench: %g ms (+-%g) done in %.0f s'
                      % (rtt, jitter, time.monotonic() - started), file=sys.stderr)
        except EmulatorError as error:
            print('emulator_bench: %s' % error, file=sys.stderr)
            return 2
    cli.write(args.out, 'emulator_accuracy.json', results)
    text = table(results)
    cli.write(args.out, 'emulator_accuracy.md', '# Link emulator accuracy\n\n' + text + '\n')
    print('\nLink emulator accuracy (round trip a -> b -> a)\n\n' + text + '\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
