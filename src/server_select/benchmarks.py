"""``make bench``: the second paper's tables and the package's throughput, measured here.

Runs against a roscore it starts on a free port; every benchmark prints figures and
writes JSON to ``--out``, and ``REPORT.md`` puts them beside the paper's numbers (labelled
as the paper's). Nothing here asserts a timing. ``--tiny`` runs each benchmark once in a
minimal configuration (the smoke test of ``make test``).
"""

import argparse
import collections
import contextlib
import io
import json
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import xmlrpc.client

import numpy as np

from server_select import emulator_bench, testbed
from server_select.stats import summarize
from server_select.usage import measure

PAPER_TABLE2 = {'ros': {'max_us': 881, 'mean_us': 408, 'sd_us': 47.2},
                'socket': {'max_us': 544, 'mean_us': 346, 'sd_us': 83.9}}
PAPER_TABLE1 = {'local': {'robot_cpu': 41.4, 'server_cpu': 0.7},
                'offload': {'robot_cpu': 1.8, 'server_cpu': 24.3}}
PY = [sys.executable, '-m']


def free_port():
    with contextlib.closing(socket.socket()) as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


class Roscore(object):
    """A roscore on a free port, its URI exported to this process and its children."""

    def __init__(self, log_dir):
        self.port = free_port()
        self.uri = 'http://127.0.0.1:%d' % self.port
        self.log_dir = log_dir
        self.proc = None

    def __enter__(self):
        os.environ['ROS_MASTER_URI'] = self.uri
        os.environ.setdefault('ROS_HOME', self.log_dir)
        self.proc = subprocess.Popen(['roscore', '-p', str(self.port)],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                     start_new_session=True)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            try:
                xmlrpc.client.ServerProxy(self.uri).getPid('/bench')
                return self
            except OSError:
                time.sleep(0.2)
        raise RuntimeError('roscore did not start on port %d' % self.port)

    def __exit__(self, *exc):
        os.killpg(self.proc.pid, 2)
        try:
            self.proc.wait(15)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, 9)
        return False


def node_pid(name):
    import rosgraph
    from server_select.usage_node import node_pid as lookup
    return lookup(rosgraph.Master('/bench'), name)


@contextlib.contextmanager
def fleet(log, **args):
    """bench_fleet.launch with ``args``; yields once robot1 and server1 are registered."""
    cmd = ['roslaunch', 'server_select', 'bench_fleet.launch'] + \
        ['%s:=%s' % kv for kv in sorted(args.items())]
    with open(log, 'a') as stream:
        proc = subprocess.Popen(cmd, stdout=stream, stderr=subprocess.STDOUT,
                                start_new_session=True)
    try:
        deadline = time.monotonic() + 40
        while True:
            try:
                node_pid('/robot1'), node_pid('/server1')
                break
            except Exception:
                if time.monotonic() > deadline or proc.poll() is not None:
                    raise RuntimeError('bench fleet did not come up (see %s)' % log)
                time.sleep(0.3)
        yield proc
    finally:
        os.killpg(proc.pid, 2)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, 9)
            proc.wait()


class ReportListener(object):
    """task_report messages received by this process (the benchmark driver)."""

    def __init__(self):
        import rospy
        from server_select.msg import TaskReport
        self.lock = threading.Lock()
        self.reports = []
        self.sub = rospy.Subscriber('task_report', TaskReport, self.on_report, queue_size=10000)

    def on_report(self, msg):
        with self.lock:
            self.reports.append((time.monotonic(), msg))

    def between(self, start, end, kind):
        with self.lock:
            return [m for t, m in self.reports if start <= t < end and m.kind == kind]


def us(summary):
    return dict((k, v * 1e6 if k != 'n' else v) for k, v in summary.items())


# -- Table 2: topic vs socket ------------------------------------------------------------

def topic_vs_socket(size, count, nodelay=True, interval=0.01):
    port = free_port()
    receiver = subprocess.Popen(PY + ['server_select.latency_bench', 'receiver', '--port',
                                      str(port), '--count', str(count)] +
                                ([] if nodelay else ['--nagle']),
                                stdout=subprocess.PIPE, universal_newlines=True)
    if receiver.stdout.readline().strip() != 'ready':
        raise RuntimeError('latency receiver did not start')
    subprocess.run(PY + ['server_select.latency_bench', 'sender', '--port', str(port),
                         '--count', str(count), '--size', str(size),
                         '--interval', str(interval)], check=True)
    out, _ = receiver.communicate(timeout=180)
    data = json.loads(out.strip().splitlines()[-1])
    return {'size': size, 'nodelay': nodelay, 'count': count,
            'ros_us': us(summarize(data['ros'])), 'socket_us': us(summarize(data['socket']))}


def bench_table2(tiny):
    count = 20 if tiny else 500
    runs = [topic_vs_socket(4, count)]
    sizes = [4, 1024] if tiny else [4, 1024, 65536, 1 << 20]
    for size in sizes[1:]:
        runs.append(topic_vs_socket(size, count if size < 1 << 20 else max(20, count // 5),
                                    interval=0.01 if size < 1 << 20 else 0.05))
    runs.append(topic_vs_socket(4, count, nodelay=False))
    return runs


# -- LatencyProbe vs socket echo ---------------------------------------------------------

def bench_probe_vs_echo(tiny, log):
    count = 20 if tiny else 300
    port = free_port()
    echo = subprocess.Popen(PY + ['server_select.netbench', 'echo-server', '--port', str(port)],
                            stdout=subprocess.PIPE, universal_newlines=True)
    try:
        echo.stdout.readline()
        out = subprocess.run(PY + ['server_select.netbench', 'echo-client', '--host',
                                   '127.0.0.1', '--port', str(port), '--count', str(count)],
                             stdout=subprocess.PIPE, universal_newlines=True, check=True)
        socket_rtt = json.loads(out.stdout)['rtt']
    finally:
        echo.kill()
        echo.wait()
    with fleet(log, task_rate='1'):
        out = subprocess.run(PY + ['server_select.netbench', 'probe-client', '--server-id', '1',
                                   '--count', str(count), '--interval', '0.01'],
                             stdout=subprocess.PIPE, universal_newlines=True, check=True)
    probe = json.loads(out.stdout.strip().splitlines()[-1])
    return {'socket_echo_us': us(summarize(socket_rtt)), 'probe_us': us(summarize(probe['rtt'])),
            'probe_failed': probe['failed']}


# -- Table 1: robot CPU with and without offloading ---------------------------------------

def bench_table1(tiny, log, area):
    """CPU% and RSS of robot and server while the robot handles 640x480 frames at 5 fps."""
    window, repeats = (3.0, 1) if tiny else (20.0, 3)
    result = {'frame_rate': 5, 'window_s': window, 'repeats': repeats}
    for label, mode in (('local', 'local'), ('offload', 'select')):
        samples = []
        for _ in range(repeats):
            with fleet(log, mode=mode, sort_tasks='false', image_source='search:' + area,
                       frame_rate='5'):
                time.sleep(4.0)   # first frames: selection, cascade loading
                pids = {'robot': node_pid('/robot1'), 'server': node_pid('/server1')}
                usage = measure(list(pids.values()), window)
            samples.append(dict((k, usage[pid]) for k, pid in pids.items()))
        result[label] = dict(
            ('%s_%s' % (who, what), statistics.median(s[who][what] for s in samples))
            for who in ('robot', 'server') for what in ('cpu_percent', 'rss_mb'))
    return result


# -- throughput ----------------------------------------------------------------------------

def offered_load(log, listener, kind, unit, rates, window, **fleet_args):
    """For each offered rate: achieved completions/s, failures and round trips of ``kind``.

    Each rate runs in a fresh fleet; the window starts 4 s in (selection, start-up) and
    reports of tasks resolved in it are counted.
    """
    rows = []
    for rate in rates:
        rate_arg = {'hz': 'task_rate', 'fps': 'frame_rate'}[unit]
        with fleet(log, **dict(fleet_args, **{rate_arg: str(rate)})):
            time.sleep(4.0)
            start = time.monotonic()
            time.sleep(window)
            end = time.monotonic()
            time.sleep(1.0)
        reports = listener.between(start, end, kind)
        ok = [r.rtt for r in reports if r.ok]
        rows.append({'offered_' + unit: rate, 'achieved_' + unit: len(ok) / window,
                     'failed': sum(1 for r in reports if not r.ok),
                     'rtt_ms': dict((k, v * 1e3) for k, v in summarize(ok).items() if k != 'n')})
    return rows


def bench_sort_throughput(tiny, log, listener):
    """Achieved tasks/s and round trips as the offered sort-task rate grows."""
    return offered_load(log, listener, 'sort', 'hz',
                        [20, 100] if tiny else [10, 50, 100, 200, 400, 800, 1600, 3200],
                        2.0 if tiny else 8.0, task_timeout='5')


def bench_image_throughput(tiny, log, listener, area):
    """Frames per second one server sustains for one robot (640x480 bgr8)."""
    return offered_load(log, listener, 'image', 'fps', [10] if tiny else [10, 15, 20, 30],
                        3.0 if tiny else 10.0, sort_tasks='false', image_source='search:' + area)


def bench_sort_breakdown(tiny, log, listener):
    """Where a sort task's round trip goes: (de)serialization, sort, transport."""
    from rospy.numpy_msg import numpy_msg
    from server_select.msg import SortResult, SortTask
    from server_select.sort_task import make_values, sort_values
    rng = np.random.default_rng(0)
    rows = []
    for size in ([1000, 100000] if tiny else [1000, 1000000]):
        values = make_values(rng, size)
        reps = 5 if (tiny or size > 100000) else 200

        def timed(fn):
            times = []
            for _ in range(reps):
                start = time.perf_counter()
                fn()
                times.append(time.perf_counter() - start)
            return statistics.median(times)
        task = numpy_msg(SortTask)(robot_id=1, task_id=1, server_id=1, data=values)
        buf = io.BytesIO()
        task.serialize(buf)
        wire = buf.getvalue()
        result = numpy_msg(SortResult)(robot_id=1, task_id=1, server_id=1, ok=True,
                                       data=np.sort(values))
        rbuf = io.BytesIO()
        result.serialize(rbuf)
        rwire = rbuf.getvalue()
        parts = {
            'serialize_task': timed(lambda: task.serialize(io.BytesIO())),
            'deserialize_task': timed(lambda: numpy_msg(SortTask)().deserialize(wire)),
            'sort': timed(lambda: sort_values(values, size)),
            'serialize_result': timed(lambda: result.serialize(io.BytesIO())),
            'deserialize_result': timed(lambda: numpy_msg(SortResult)().deserialize(rwire)),
        }
        rate = 20 if size <= 1000 else 1
        with fleet(log, task_rate=str(rate), task_size=str(size), task_timeout='10'):
            time.sleep(5.0)
            start = time.monotonic()
            time.sleep(2.0 if tiny else 10.0)
            end = time.monotonic()
            time.sleep(2.0 if size > 1000 else 0.5)
        ok = [r.rtt for r in listener.between(start, end, 'sort') if r.ok]
        rtt = statistics.median(ok) if ok else float('nan')
        rows.append({'size': size, 'bytes': len(wire), 'tasks': len(ok),
                     'rtt_ms': rtt * 1e3,
                     'parts_ms': dict((k, v * 1e3) for k, v in parts.items()),
                     'transport_ms': (rtt - sum(parts.values())) * 1e3})
    return rows


# -- report ---------------------------------------------------------------------------------

def report(results):
    lines = ['# Benchmarks', '',
             'Measured by `make bench` on this machine (%d cores); the paper\'s figures are '
             'copied from "Evaluation for ROS based Distribute Robot Searching System" and '
             'labelled as such.' % os.cpu_count(), '']
    t2 = results.get('table2')
    if t2:
        base = t2[0]
        lines += ['## Table 2: ROS topic vs raw TCP socket, one host, one-way latency', '',
                  '%d messages each, interleaved (each ROS message followed by a socket '
                  'message), 4-byte payload + timestamp, tcp_nodelay on.' % base['count'], '',
                  '| us | ROS (here) | socket (here) | ROS (paper) | socket (paper) |',
                  '|---|---|---|---|---|']
        for key, paper in (('max', 'max_us'), ('mean', 'mean_us'), ('sd', 'sd_us'),
                           ('median', None), ('p99', None)):
            lines.append('| %s | %.0f | %.0f | %s | %s |' % (
                key, base['ros_us'][key], base['socket_us'][key],
                PAPER_TABLE2['ros'][paper] if paper else '-',
                PAPER_TABLE2['socket'][paper] if paper else '-'))
        lines += ['', 'Payload sizes and Nagle (median / p99 us):', '',
                  '| payload | tcp_nodelay | n | ROS median | ROS p99 | socket median | socket p99 '
                  '| ROS / socket (median) |', '|---|---|---|---|---|---|---|---|']
        for r in t2:
            lines.append('| %d B | %s | %d | %.0f | %.0f | %.0f | %.0f | %.2f |' % (
                r['size'], 'on' if r['nodelay'] else 'off', r['count'], r['ros_us']['median'],
                r['ros_us']['p99'], r['socket_us']['median'], r['socket_us']['p99'],
                r['ros_us']['median'] / r['socket_us']['median']))
        lines.append('')
    pe = results.get('probe_vs_echo')
    if pe:
        lines += ['## LatencyProbe round trip vs raw socket echo, one host', '',
                  '| us | LatencyProbe (persistent) | socket echo |', '|---|---|---|']
        for key in ('median', 'mean', 'p99', 'max'):
            lines.append('| %s | %.0f | %.0f |' % (key, pe['probe_us'][key],
                                                   pe['socket_echo_us'][key]))
        lines.append('')
    em = results.get('emulated')
    if em:
        lines += ['## The same over an emulated link (testbed, 2 namespaces)', '',
                  emulator_bench.table(em), '']
    t1 = results.get('table1')
    if t1:
        lines += ['## Table 1: CPU with and without offloading', '',
                  'Robot handling 640x480 frames at %d fps (Haar face cascade); CPU%% over %.0f s '
                  '(100 = one core), median of %d runs.' % (t1['frame_rate'], t1['window_s'],
                                                            t1['repeats']), '',
                  '| | robot CPU % (here) | server CPU % (here) | robot RSS MiB | server RSS MiB '
                  '| robot CPU % (paper) | server CPU % (paper) |', '|---|---|---|---|---|---|---|']
        for label in ('local', 'offload'):
            r, p = t1[label], PAPER_TABLE1[label]
            lines.append('| %s | %.1f | %.1f | %.0f | %.0f | %.1f | %.1f |' % (
                'robot detects itself' if label == 'local' else 'offloaded to the server',
                r['robot_cpu_percent'], r['server_cpu_percent'], r['robot_rss_mb'],
                r['server_rss_mb'], p['robot_cpu'], p['server_cpu']))
        lines.append('')
    for key, title, unit in (('sort_throughput', 'Sort-task throughput, one robot, one server '
                              '(1000 int32)', 'hz'),
                             ('image_throughput', 'Image throughput, one robot, one server '
                              '(640x480 bgr8, face cascade)', 'fps')):
        rows = results.get(key)
        if not rows:
            continue
        lines += ['## %s' % title, '',
                  '| offered /s | achieved /s | failed | RTT median ms | p95 ms | p99 ms |',
                  '|---|---|---|---|---|---|']
        for r in rows:
            rtt = r['rtt_ms']
            lines.append('| %g | %.1f | %d | %s | %s | %s |' % (
                r['offered_' + unit], r['achieved_' + unit], r['failed'],
                *('%.2f' % rtt[k] if k in rtt else '-' for k in ('median', 'p95', 'p99'))))
        lines.append('')
    bd = results.get('sort_breakdown')
    if bd:
        lines += ['## Where a sort task\'s round trip goes (median ms)', '',
                  '| values | wire bytes | round trip | serialize task | deserialize task | sort '
                  '| serialize result | deserialize result | transport + rest |',
                  '|---|---|---|---|---|---|---|---|---|']
        for r in bd:
            p = r['parts_ms']
            lines.append('| %d | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |' % (
                r['size'], r['bytes'], r['rtt_ms'], p['serialize_task'], p['deserialize_task'],
                p['sort'], p['serialize_result'], p['deserialize_result'], r['transport_ms']))
        lines.append('')
    return '\n'.join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--out', default='results/bench')
    parser.add_argument('--tiny', action='store_true', help='one minimal run of each benchmark')
    parser.add_argument('--only', default='', help='comma-separated subset: table2, probe, '
                        'table1, sort, image, breakdown, emulated (the report then also shows '
                        'earlier results found in --out)')
    args = parser.parse_args(argv)
    only = set(filter(None, args.only.split(',')))
    wanted = lambda name: not only or name in only
    os.makedirs(args.out, exist_ok=True)
    area = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'config',
                        'search_area.yaml')
    results = collections.OrderedDict()
    with tempfile.TemporaryDirectory(prefix='bench') as tmp:
        log = os.path.join(args.out, 'bench_nodes.log')
        open(log, 'w').close()
        with Roscore(tmp):
            import rospy
            rospy.init_node('bench', anonymous=True, disable_signals=True)
            listener = ReportListener()
            steps = [('table2', lambda: bench_table2(args.tiny)),
                     ('probe', lambda: bench_probe_vs_echo(args.tiny, log)),
                     ('table1', lambda: bench_table1(args.tiny, log, area)),
                     ('sort', lambda: bench_sort_throughput(args.tiny, log, listener)),
                     ('image', lambda: bench_image_throughput(args.tiny, log, listener, area)),
                     ('breakdown', lambda: bench_sort_breakdown(args.tiny, log, listener))]
            keys = {'table2': 'table2', 'probe': 'probe_vs_echo', 'table1': 'table1',
                    'sort': 'sort_throughput', 'image': 'image_throughput',
                    'breakdown': 'sort_breakdown'}
            for name, step in steps:
                if wanted(name):
                    started = time.monotonic()
                    results[keys[name]] = step()
                    print('bench: %s done in %.0f s' % (name, time.monotonic() - started),
                          file=sys.stderr, flush=True)
            rospy.signal_shutdown('benchmarks done')
    if wanted('emulated') and not args.tiny:
        ok, why = testbed.available()
        if ok:
            with tempfile.TemporaryDirectory(prefix='bench_emulated') as work:
                results['emulated'] = [emulator_bench.measure_case(rtt, 0.0, work, 300, 100)
                                       for rtt in (5.0, 20.0)]
        else:
            print('bench: emulated link skipped: %s' % why, file=sys.stderr)
    for key, value in results.items():
        with open(os.path.join(args.out, '%s.json' % key), 'w') as stream:
            json.dump(value, stream, indent=1)
    if only:  # the report also shows what earlier runs left in --out
        for key in ('table2', 'probe_vs_echo', 'emulated', 'table1', 'sort_throughput',
                    'image_throughput', 'sort_breakdown'):
            path = os.path.join(args.out, '%s.json' % key)
            if key not in results and os.path.exists(path):
                with open(path) as stream:
                    results[key] = json.load(stream)
    text = report(results)
    with open(os.path.join(args.out, 'REPORT.md'), 'w') as stream:
        stream.write(text + '\n')
    print(text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
