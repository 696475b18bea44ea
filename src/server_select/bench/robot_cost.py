"""What a robot node costs its host (``make bench-robot``): CPU and resident memory by
profile, number of servers and workload, on this host and on an emulated Raspberry Pi 3.

A cell is ``host:workload:servers``: ``here`` or ``pi`` (the robot's process in a cgroup
with one Pi 3 core, ``--pi-share`` of this host's core per 10 ms, and 1 GiB: the testbed's
``like: pi3``); ``sort`` (sort tasks at 2/s) or ``camera`` (frames of a camera topic,
``sensor_msgs/CompressedImage`` 640 x 480 JPEG at 5 fps from a publisher of the bench's,
offloaded compressed); 4, 10 or 30 servers. For each cell the two profiles run side by
side, each under a roscore of its own (manager, the servers, one robot). Once each
robot's first task is answered and after ``--warmup`` s, over ``--seconds`` s: the robot's
CPU (% of this host's core; on a Pi, also % of the Pi core) and RSS. ``--repeats`` times;
printed: median (min-max). With ``--profile S`` (S seconds), py-spy then samples each
robot of the first cell and the table says where its time goes, by part. Nothing is
asserted.

    python -m server_select.bench.robot_cost --repeats 3 --profile 30
"""

import argparse
import collections
import contextlib
import os
import subprocess
import sys
import tempfile
import time

from server_select.bench import camera, cli, robot_profile
from server_select.bench.harness import Roscore, launched, pid_or_none
from server_select.core.util.procs import measure, stop_group, wait_until
from server_select.core.util.tables import markdown_table, median_range
from server_select.testbed.cpu import CpuLimit
from server_select.testbed.fields import PI3

PROFILES = ('paper', 'fleet')
CELLS = 'here:sort:4,here:sort:10,here:sort:30,here:camera:4,pi:sort:4,pi:camera:4'
CAMERA_TOPIC = '/camera/image_raw/compressed'
WORKLOADS = {
    'sort': {'task_rate': '2'},
    'camera': {'sort_tasks': 'false', 'image_topic': CAMERA_TOPIC,
               'image_transport': 'compressed', 'frame_rate': '5'},
}

Cell = collections.namedtuple('Cell', 'host workload servers')


def cells(text):
    parsed = []
    for item in text.split(','):
        host, workload, servers = item.split(':')
        if host not in ('here', 'pi') or workload not in WORKLOADS:
            raise ValueError('a cell is here|pi:sort|camera:N, got %r' % item)
        parsed.append(Cell(host, workload, int(servers)))
    return parsed


def launch_file(path, profile, cell, extra=None):
    """A launch file: the manager, ``cell.servers`` servers, one robot (with ``extra``
    robot.launch arguments, ``{name: value}``)."""
    ids = ','.join(str(s) for s in range(1, cell.servers + 1))
    listed = '' if profile == 'fleet' else ids
    robot = dict(WORKLOADS[cell.workload], robot_id='1', servers=listed or ids,
                 profile=profile, output='log', summary_period='3600', **(extra or {}))
    arg = '<arg name="%s" value="%s"/>'
    text = ['<launch>',   # servers.launch passes what it is given on to each server
            '<arg name="profile" default="%s"/>' % profile,
            '<arg name="servers" default="%s"/>' % ids, '<arg name="output" default="log"/>',
            '<include file="$(find server_select)/launch/servers.launch" '
            'pass_all_args="true"/>',
            '<include file="$(find server_select)/launch/manager.launch">',
            arg % ('profile', profile), arg % ('robots', '' if profile == 'fleet' else '1'),
            arg % ('servers', listed), arg % ('output', 'log'), '</include>',
            '<include file="$(find server_select)/launch/robot.launch">']
    text += [arg % item for item in sorted(robot.items())] + ['</include>']
    with open(path, 'w') as stream:
        stream.write('\n'.join(text + ['</launch>']) + '\n')


def launch_args(text):
    """``{name: value}`` of ``name:=value`` words."""
    pairs = [word.split(':=', 1) for word in text.split()]
    if any(len(pair) != 2 or not pair[0] for pair in pairs):
        raise argparse.ArgumentTypeError('expected name:=value ..., got %r' % text)
    return dict(pairs)


def answered(master):
    """Whether a task of robot 1 was answered (one ``task_report`` with ok)."""
    env = dict(os.environ, ROS_MASTER_URI=master)
    try:
        out = subprocess.run(['rostopic', 'echo', '-n', '1', '/task_report/ok'], env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                             universal_newlines=True, timeout=20).stdout
    except subprocess.TimeoutExpired:
        return False
    return 'True' in out


def context_switches(pid):
    """Context switches of every thread of ``pid`` so far: about its threads' wake-ups,
    which a sampling profiler does not see and which cost a quiet node most of its CPU."""
    total = 0
    for task in os.listdir('/proc/%d/task' % pid):
        try:
            with open('/proc/%d/task/%s/status' % (pid, task)) as stream:
                total += sum(int(line.split()[1]) for line in stream
                             if line.split(':')[0].endswith('ctxt_switches'))
        except OSError:      # the thread ended
            pass
    return total


def start(cell, profile, master, work, tag, fleets, extra=None):
    """The fleet of ``profile`` under ``master`` (and the bench's camera), entered into the
    ExitStack ``fleets``: robot 1's pid."""
    path = os.path.join(work, '%s_%s.launch' % (tag, profile))
    launch_file(path, profile, cell, extra)
    log = path[:-len('.launch')] + '.log'
    if cell.workload == 'camera':     # the camera driver: not the robot's work
        with open(log, 'a') as stream:
            fleets.callback(stop_group, subprocess.Popen(
                [sys.executable, '-m', 'server_select.bench.robot_cost', '--camera',
                 CAMERA_TOPIC, '--rate', '5'], stdout=stream, stderr=subprocess.STDOUT,
                env=dict(os.environ, ROS_MASTER_URI=master), start_new_session=True),
                timeout=20.0)
    return fleets.enter_context(launched(path, [], log, master, ['/robot1'],
                                         60.0 + cell.servers))['/robot1']


def one_cell(cell, options, work, tag):
    """``{profile: {'cpu', 'rss', 'pi_cpu'?, 'profile'?}}`` of one run of ``cell``."""
    with Roscore(work) as first, Roscore(work) as second, contextlib.ExitStack() as fleets:
        masters = dict(zip(PROFILES, (first.uri, second.uri)))
        pids = dict((profile, start(cell, profile, master, work, tag, fleets,
                                    options.robot_args)) for profile, master in masters.items())
        if cell.host == 'pi':
            for profile, pid in pids.items():
                limit = CpuLimit('ssbr%d-%s' % (os.getpid(), profile), options.pi_share,
                                 PI3['cpu_period'] * 1000, PI3['memory']).create()
                fleets.callback(limit.remove)
                limit.join(pid)
        for profile, master in masters.items():
            if not wait_until(lambda: answered(master), 120.0, 0.5):
                raise RuntimeError('no task of the %s robot was answered (%s)'
                                   % (profile, work))
        time.sleep(options.warmup)          # windows fill, probing settles
        switches = dict((p, context_switches(pid)) for p, pid in pids.items())
        servers = dict((p, pid_or_none('/server1', m)) for p, m in masters.items())
        usage = measure(list(pids.values()) + [s for s in servers.values() if s],
                        options.seconds)
        switches = dict((p, (context_switches(pid) - switches[p]) / options.seconds)
                        for p, pid in pids.items())
        sampled = dict((p, robot_profile.sample(pid, options.profile, work, p))
                       for p, pid in pids.items()) if tag == 'profiled' else {}
    result = {}
    for profile, pid in pids.items():
        used = usage.get(pid, {})
        result[profile] = {'cpu': used.get('cpu_percent'), 'rss': used.get('rss_mb'),
                           'server_rss': usage.get(servers[profile], {}).get('rss_mb'),
                           'wakeups': switches[profile], 'parts': sampled.get(profile)}
        if cell.host == 'pi' and used:
            result[profile]['pi_cpu'] = used['cpu_percent'] / options.pi_share
    return result


def table(runs):
    rows = []
    for key in sorted(set((r['cell'], r['profile']) for r in runs),
                      key=lambda k: (CELLS + ',' + k[0]).index(k[0]) * 2 + PROFILES.index(k[1])):
        each = [r for r in runs if (r['cell'], r['profile']) == key]
        host, workload, servers = key[0].split(':')
        cpu = [r['cpu'] for r in each if r['cpu'] is not None]
        pi = [r['pi_cpu'] for r in each if r.get('pi_cpu') is not None]
        rss = [r['rss'] for r in each if r['rss'] is not None]
        wakeups = [r['wakeups'] for r in each if r.get('wakeups') is not None]
        server = [r['server_rss'] for r in each if r.get('server_rss') is not None]
        rows.append(['this host' if host == 'here' else 'Pi 3 (emulated)', workload, servers,
                     key[1], median_range(cpu, '%.2f') if cpu else '-',
                     median_range(pi, '%.1f') if pi else '-',
                     median_range(rss, '%.0f') if rss else '-',
                     median_range(wakeups, '%.0f') if wakeups else '-',
                     median_range(server, '%.0f') if server else '-'])
    return markdown_table(['robot host', 'workload', 'servers', 'profile',
                           'CPU % of this host\'s core', 'CPU % of the Pi core', 'RSS MiB',
                           'thread wake-ups/s', 'a server\'s RSS MiB'], rows)


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--cells', default=CELLS, help='host:workload:servers,...')
    parser.add_argument('--repeats', type=int, default=3)
    parser.add_argument('--warmup', type=float, default=15.0)
    parser.add_argument('--seconds', type=float, default=40.0)
    parser.add_argument('--pi-share', type=float, default=PI3['cpu'],
                        help='of this host\'s core that stands for a Pi 3 core')
    parser.add_argument('--profile', type=float, default=0.0,
                        help='s of py-spy sampling of each robot of the first cell (0: none)')
    parser.add_argument('--robot-args', default='', type=launch_args,
                        help='more robot.launch arguments for both robots (name:=value ...)')
    parser.add_argument('--camera', help=argparse.SUPPRESS)
    parser.add_argument('--rate', type=float, default=5.0, help=argparse.SUPPRESS)
    options, _ros = parser.parse_known_args(argv)
    if options.camera:
        return camera.publish(options.camera, options.rate)
    runs, parts = [], {}
    work = tempfile.mkdtemp(prefix='robot_cost_')
    for repeat in range(1, options.repeats + 1):
        for index, cell in enumerate(cells(options.cells)):
            tag = 'profiled' if options.profile and repeat == 1 and index == 0 else \
                'r%d_c%d' % (repeat, index)
            result = one_cell(cell, options, work, tag)
            for profile, figures in result.items():
                sampled = figures.pop('parts')
                if sampled:
                    parts[profile] = sampled
                runs.append(dict(figures, cell=':'.join(map(str, cell)), profile=profile,
                                 repeat=repeat))
            print('repeat %d, %s: %s' % (repeat, ':'.join(map(str, cell)), ', '.join(
                '%s %.2f %%' % (p, f['cpu'] or 0) for p, f in result.items())),
                file=sys.stderr, flush=True)
    text = table(runs)
    print('\nRobot node cost, median of %d runs (min-max), %g s each after %g s (logs in %s)\n\n%s'
          % (options.repeats, options.seconds, options.warmup, work, text))
    if parts:
        where = robot_profile.table(parts)
        print('\nWhere a robot\'s time goes (%s, py-spy, %g s; %% of its samples on a CPU)\n\n%s'
              % (options.cells.split(',')[0], options.profile, where))
        text += '\n\n' + where
    cli.write(options.out, 'robot_cost.json', {'runs': runs, 'parts': parts})
    cli.write(options.out, 'robot_cost.md', text + '\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
