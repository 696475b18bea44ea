"""``REPORT.md`` of ``make bench``: the measured figures beside the paper's (labelled)."""

import os

from server_select.core.util.tables import markdown_table

PAPER_TABLE2 = {'ros': {'max_us': 881, 'mean_us': 408, 'sd_us': 47.2},
                'socket': {'max_us': 544, 'mean_us': 346, 'sd_us': 83.9}}
PAPER_TABLE1 = {'local': {'robot_cpu': 41.4, 'server_cpu': 0.7},
                'offload': {'robot_cpu': 1.8, 'server_cpu': 24.3}}


def table2(t2):
    base = t2[0]

    def paper(path, key):
        return PAPER_TABLE2[path][key] if key else '-'
    main = markdown_table(
        ('us', 'ROS (here)', 'socket (here)', 'ROS (paper)', 'socket (paper)'),
        [(key, '%.0f' % base['ros_us'][key], '%.0f' % base['socket_us'][key],
          paper('ros', p), paper('socket', p))
         for key, p in (('max', 'max_us'), ('mean', 'mean_us'), ('sd', 'sd_us'),
                        ('median', None), ('p99', None))])
    sizes = markdown_table(
        ('payload', 'tcp_nodelay', 'n', 'ROS median', 'ROS p99', 'socket median', 'socket p99',
         'ROS / socket (median)'),
        [('%d B' % r['size'], 'on' if r['nodelay'] else 'off', r['count'],
          '%.0f' % r['ros_us']['median'], '%.0f' % r['ros_us']['p99'],
          '%.0f' % r['socket_us']['median'], '%.0f' % r['socket_us']['p99'],
          '%.2f' % (r['ros_us']['median'] / r['socket_us']['median'])) for r in t2])
    return ['## Table 2: ROS topic vs raw TCP socket, one host, one-way latency', '',
            '%d messages each, interleaved (each ROS message followed by a socket message), '
            '4-byte payload + timestamp, tcp_nodelay on.' % base['count'], '', main, '',
            'Payload sizes and Nagle (median / p99 us):', '', sizes]


def probe_vs_echo(pe):
    return ['## LatencyProbe round trip vs raw socket echo, one host', '', markdown_table(
        ('us', 'LatencyProbe (persistent)', 'socket echo'),
        [(key, '%.0f' % pe['probe_us'][key], '%.0f' % pe['socket_echo_us'][key])
         for key in ('median', 'mean', 'p99', 'max')])]


def emulated(em):
    from server_select.bench.emulator import table
    return ['## The same over an emulated link (testbed, 2 namespaces)', '', table(em)]


def table1(t1):
    def cpu(label, who):
        runs = [run[who]['cpu_percent'] for run in t1.get(label + '_runs', [])]
        spread = ' (%.1f-%.1f)' % (min(runs), max(runs)) if len(runs) > 1 else ''
        return '%.1f%s' % (t1[label][who + '_cpu_percent'], spread)
    rows = []
    for label in ('local', 'offload'):
        r, p = t1[label], PAPER_TABLE1[label]
        rows.append(('robot detects itself' if label == 'local' else 'offloaded to the server',
                     cpu(label, 'robot'), cpu(label, 'server'),
                     '%.0f' % r['robot_rss_mb'], '%.0f' % r['server_rss_mb'],
                     '%.1f' % p['robot_cpu'], '%.1f' % p['server_cpu']))
    return ['## Table 1: CPU with and without offloading', '',
            'Robot handling 640x480 frames at %d fps (Haar face cascade, the same detector '
            'settings on robot and server); CPU%% over %.0f s (100 = one core), median (min-max) '
            'of %d runs.' % (t1['frame_rate'], t1['window_s'], t1['repeats']), '',
            markdown_table(('', 'robot CPU % (here)', 'server CPU % (here)', 'robot RSS MiB',
                            'server RSS MiB', 'robot CPU % (paper)', 'server CPU % (paper)'),
                           rows)]


def throughput(rows, title, unit):
    def cells(rtt):
        return ['%.2f' % rtt[k] if k in rtt else '-' for k in ('median', 'p95', 'p99')]
    table = markdown_table(
        ('offered /s', 'achieved /s', 'failed', 'RTT median ms', 'p95 ms', 'p99 ms'),
        [['%g' % r['offered_' + unit], '%.1f' % r['achieved_' + unit], r['failed']]
         + cells(r['rtt_ms']) for r in rows])
    return ['## %s' % title, '', 'A failed task counts in the round trips at the task timeout.',
            '', table]


def breakdown(bd):
    parts = ('serialize_task', 'deserialize_task', 'sort', 'serialize_result',
             'deserialize_result')
    return ['## Where a sort task\'s round trip goes (median ms)', '', markdown_table(
        ('values', 'wire bytes', 'round trip', 'serialize task', 'deserialize task', 'sort',
         'serialize result', 'deserialize result', 'transport + rest'),
        [[r['size'], r['bytes'], '%.3f' % r['rtt_ms']]
         + ['%.3f' % r['parts_ms'][p] for p in parts] + ['%.3f' % r['transport_ms']]
         for r in bd])]


SECTIONS = [
    ('table2', table2), ('probe_vs_echo', probe_vs_echo), ('emulated', emulated),
    ('table1', table1),
    ('sort_throughput', lambda rows: throughput(
        rows, 'Sort-task throughput, one robot, one server (1000 int32)', 'hz')),
    ('image_throughput', lambda rows: throughput(
        rows, 'Image throughput, one robot, one server (640x480 bgr8, face cascade)', 'fps')),
    ('sort_breakdown', breakdown),
]


def report(results):
    """The Markdown report of whichever results are present."""
    lines = ['# Benchmarks', '',
             'Measured by `make bench` on this machine (%d cores); the paper\'s figures are '
             'copied from "Evaluation for ROS based Distribute Robot Searching System" and '
             'labelled as such.' % os.cpu_count(), '']
    for key, section in SECTIONS:
        if results.get(key):
            lines += section(results[key]) + ['']
    return '\n'.join(lines)
