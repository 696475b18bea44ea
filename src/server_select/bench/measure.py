"""The benchmarks of ``make bench``: each returns figures (JSON-ready), asserts nothing."""

import io
import json
import statistics
import subprocess
import time


from server_select.bench.harness import PY, fleet, free_port, node_pid, us
from server_select.core.util.procs import measure
from server_select.core.settings import default
from server_select.core.util.stats import summarize


# -- Table 2: topic vs socket ------------------------------------------------------------

def topic_vs_socket(size, count, nodelay=True, interval=0.01):
    port = free_port()
    receiver = subprocess.Popen(PY + ['server_select.bench.latency', 'receiver', '--port',
                                      str(port), '--count', str(count)] +
                                ([] if nodelay else ['--nagle']),
                                stdout=subprocess.PIPE, universal_newlines=True)
    if receiver.stdout.readline().strip() != 'ready':
        raise RuntimeError('latency receiver did not start')
    subprocess.run(PY + ['server_select.bench.latency', 'sender', '--port', str(port),
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
    echo = subprocess.Popen(PY + ['server_select.bench.netbench', 'echo-server', '--port',
                                  str(port)], stdout=subprocess.PIPE, universal_newlines=True)
    try:
        echo.stdout.readline()
        out = subprocess.run(PY + ['server_select.bench.netbench', 'echo-client', '--host',
                                   '127.0.0.1', '--port', str(port), '--count', str(count)],
                             stdout=subprocess.PIPE, universal_newlines=True, check=True)
        socket_rtt = json.loads(out.stdout)['rtt']
    finally:
        echo.kill()
        echo.wait()
    with fleet(log, task_rate='1'):
        out = subprocess.run(PY + ['server_select.bench.netbench', 'probe-client', '--server-id',
                                   '1', '--count', str(count), '--interval', '0.01'],
                             stdout=subprocess.PIPE, universal_newlines=True, check=True)
    probe = json.loads(out.stdout.strip().splitlines()[-1])
    return {'socket_echo_us': us(summarize(socket_rtt)), 'probe_us': us(summarize(probe['rtt'])),
            'probe_failed': probe['failed']}


# -- Table 1: robot CPU with and without offloading ---------------------------------------

def started(listener, kind, log):
    """Wait for the fleet's first answered task of ``kind`` (selection made, the work's
    files loaded): figures are of the steady state. Up to 120 s: a first camera frame
    detected by a robot that runs at the lowest priority beside busy tests (make test's
    background) once took over 40 s."""
    if not listener.wait_for_answer(kind, timeout=120.0):
        raise RuntimeError('the bench fleet answered no %s task (see %s)' % (kind, log))


def bench_table1(tiny, log, listener, area):
    """CPU% and RSS of robot and server while the robot handles 640x480 frames at 5 fps."""
    window, repeats = (3.0, 1) if tiny else (20.0, 3)
    result = {'frame_rate': 5, 'window_s': window, 'repeats': repeats}
    for label, mode in (('local', 'local'), ('offload', 'select')):
        samples = []
        for _ in range(repeats):
            with fleet(log, mode=mode, sort_tasks='false', image_source='search:' + area,
                       frame_rate='5'):
                started(listener, 'image', log)
                pids = {'robot': node_pid('/robot1'), 'server': node_pid('/server1')}
                usage = measure(list(pids.values()), window)
            samples.append(dict((k, usage[pid]) for k, pid in pids.items()))
        result[label] = dict(
            ('%s_%s' % (who, what), statistics.median(s[who][what] for s in samples))
            for who in ('robot', 'server') for what in ('cpu_percent', 'rss_mb'))
        result[label + '_runs'] = samples     # every run, for the spread
    return result


# -- throughput ----------------------------------------------------------------------------

def offered_load(log, listener, kind, unit, rates, window, **fleet_args):
    """For each offered rate: achieved completions/s, failures and round trips of ``kind``.

    Each rate runs in a fresh fleet; the window starts at its first answer (selection,
    start-up) and the reports received in it are counted; a failed task counts in the
    round trips at the task timeout.
    """
    timeout = float(fleet_args.get('task_timeout', default('task_timeout')))
    rows = []
    for rate in rates:
        rate_arg = {'hz': 'task_rate', 'fps': 'frame_rate'}[unit]
        with fleet(log, **dict(fleet_args, **{rate_arg: str(rate)})):
            started(listener, kind, log)
            start = time.monotonic()
            time.sleep(window)
            end = time.monotonic()
        reports = listener.between(start, end, kind)
        rtts = summarize([r.rtt if r.ok else timeout for r in reports])
        rows.append({'offered_' + unit: rate,
                     'achieved_' + unit: sum(r.ok for r in reports) / window,
                     'failed': sum(1 for r in reports if not r.ok),
                     'rtt_ms': dict((k, v * 1e3) for k, v in rtts.items() if k != 'n')})
    return rows


def bench_sort_throughput(tiny, log, listener):
    """Achieved tasks/s and round trips as the offered sort-task rate grows."""
    return offered_load(log, listener, 'sort', 'hz',
                        [50] if tiny else [10, 50, 100, 200, 400, 800, 1600, 3200],
                        2.0 if tiny else 8.0, task_timeout='5')


def bench_image_throughput(tiny, log, listener, area):
    """Frames per second one server sustains for one robot (640x480 bgr8)."""
    # tiny (make test's smoke run, at nice 19 beside two other streams): a rate such a host
    # keeps up with; at 10 frames/s one CI run answered none within the task timeout
    return offered_load(log, listener, 'image', 'fps', [2] if tiny else [10, 15, 20, 30],
                        5.0 if tiny else 10.0, sort_tasks='false', image_source='search:' + area)


def bench_sort_breakdown(tiny, log, listener):
    """Where a sort task's round trip goes: (de)serialization, sort, transport."""
    import random
    from server_select.msg import SortResult, SortTask
    from server_select.core.flow.sort_kernel import make_values, sort_values
    rng = random.Random(0)
    rows = []
    for size in ([1000] if tiny else [1000, 1000000]):
        values = make_values(rng, size)
        reps = 5 if (tiny or size > 100000) else 200

        def timed(fn):
            times = []
            for _ in range(reps):
                start = time.perf_counter()
                fn()
                times.append(time.perf_counter() - start)
            return statistics.median(times)
        task = SortTask(robot_id=1, task_id=1, server_id=1, data=values)
        buf = io.BytesIO()
        task.serialize(buf)
        wire = buf.getvalue()
        result = SortResult(robot_id=1, task_id=1, server_id=1, ok=True,
                            data=sorted(values))
        rbuf = io.BytesIO()
        result.serialize(rbuf)
        rwire = rbuf.getvalue()
        parts = {
            'serialize_task': timed(lambda: task.serialize(io.BytesIO())),
            'deserialize_task': timed(lambda: SortTask().deserialize(wire)),
            'sort': timed(lambda: sort_values(values, size)),
            'serialize_result': timed(lambda: result.serialize(io.BytesIO())),
            'deserialize_result': timed(lambda: SortResult().deserialize(rwire)),
        }
        rate = 20 if size <= 1000 else 1
        with fleet(log, task_rate=str(rate), task_size=str(size), task_timeout='10'):
            started(listener, 'sort', log)
            start = time.monotonic()
            time.sleep(2.0 if tiny else 10.0)
            end = time.monotonic()
        ok = [r.rtt for r in listener.between(start, end, 'sort') if r.ok]
        rtt = statistics.median(ok) if ok else float('nan')
        rows.append({'size': size, 'bytes': len(wire), 'tasks': len(ok),
                     'rtt_ms': rtt * 1e3,
                     'parts_ms': dict((k, v * 1e3) for k, v in parts.items()),
                     'transport_ms': (rtt - sum(parts.values())) * 1e3})
    return rows
