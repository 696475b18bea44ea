"""Where a robot node's time goes (bench-robot's ``--profile``).

:func:`sample` runs py-spy (a sampling profiler, from PyPI) on a running node and sorts
its samples into parts of the robot by the innermost frame of this package on each
stack: probes, windows and ranking, ranking messages, flags, the task path, membership,
the seal (signing and checking), the node itself (a publisher that only passes a message
on counts for its caller); stacks without a frame of ours by rospy's part (timers,
transport), and every stack that passes through logging to logging. Samples of a thread
waiting (in ``recv``, ``select``, a queue or a sleep) are left out.
"""

import collections
import os
import shutil
import subprocess
import sys

from server_select.core.util.tables import markdown_table

PARTS = (   # (part, what the file of the innermost frame of ours contains)
    ('probes', ('ros/prober.py', 'ros/probe_client.py', 'core/robot/probe_plan.py',
                'core/robot/probes.py', 'core/robot/answer_time.py')),
    ('windows and ranking', ('core/rule/', 'core/peers/', 'core/ranking/', 'core/manager/',
                             'core/robot/selection', 'core/robot/health.py',
                             'core/robot/refusals.py', 'core/load/', 'ros/load.py',
                             'ros/passive.py', 'core/fleet/health')),
    ('ranking messages', ('ros/view.py',)),
    ('flags', ('ros/flags.py',)),
    ('task path', ('core/flow/', 'core/robot/stream.py', 'ros/task_stream.py',
                   'ros/routing.py', 'server_select/tasks/',
                   'ros/camera.py', 'vision/', 'tasks/kinds.py')),
    ('membership', ('ros/membership.py', 'ros/graph.py', 'ros/senders.py',
                    'ros/master_watch.py')),
    ('seal', ('core/trust/',)),
    ('robot node', ('nodes/robot.py', 'core/robot/', 'ros/robot_parts.py', 'ros/runner.py',
                    'ros/node.py')),
)
# frames that only pass a call on (a SealedPublisher without a key): the caller decides
WRAPPERS = ('ros/seal.py',)
WAITING = ('recv_buff (', 'thread.py:81)', 'wait (', 'select (', 'sleep (', 'accept (',
           'poll (', '_wait_for_tstate_lock', 'readinto (')


def part_of(frames):
    """The part of one stack (a list of ``func (file:line)``, outermost first); None for
    a thread that waits."""
    if not frames or any(w in frames[-1] for w in WAITING):
        return None
    if any('logging/__init__' in f or 'rospy/impl/rosout' in f for f in frames):
        return 'logging'
    for frame in reversed(frames):
        if 'server_select/' not in frame or 'server_select/msg/' in frame or \
                'server_select/srv/' in frame or any(w in frame for w in WRAPPERS):
            continue
        for part, files in PARTS:
            if any(f in frame for f in files):
                return part
        return 'robot node'
    if any('rospy/timer.py' in f for f in frames):
        return 'rospy timers'
    if any('rospy/' in f or 'genpy/' in f for f in frames):
        return 'ROS transport and messages'
    return 'other'


def parts(raw_lines):
    """``{part: samples}`` of py-spy's raw output (``stack count`` per line)."""
    counts = collections.Counter()
    for line in raw_lines:
        stack, _, count = line.rstrip('\n').rpartition(' ')
        if not stack or not count.isdigit():
            continue
        part = part_of(stack.split(';'))
        if part is not None:
            counts[part] += int(count)
    return dict(counts)


def _py_spy():
    here = os.path.join(os.path.dirname(sys.executable), 'py-spy')
    return here if os.path.exists(here) else shutil.which('py-spy')


def sample(pid, seconds, work, name, rate=250):
    """``{part: samples}`` of node ``pid`` over ``seconds`` s; ``{}`` without py-spy."""
    tool = _py_spy()
    if tool is None:
        print('py-spy is not installed: no profile (pip install py-spy)', file=sys.stderr)
        return {}
    out = os.path.join(work, 'py-spy_%s.txt' % name)
    subprocess.run([tool, 'record', '-p', str(pid), '-d', '%d' % seconds, '-r', str(rate),
                    '-f', 'raw', '-o', out], stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL, check=False)
    try:
        with open(out) as stream:
            return parts(stream)
    except OSError:
        return {}


def table(by_profile):
    """Each part's share of a profile's samples on a CPU (%), most first."""
    profiles = sorted(by_profile)
    totals = dict((p, float(sum(by_profile[p].values())) or 1.0) for p in profiles)
    names = sorted(set(k for p in profiles for k in by_profile[p]),
                   key=lambda k: -sum(by_profile[p].get(k, 0) / totals[p] for p in profiles))
    rows = [[name] + ['%.1f' % (100.0 * by_profile[p].get(name, 0) / totals[p])
                      for p in profiles] for name in names]
    rows.append(['samples on a CPU'] + ['%d' % totals[p] for p in profiles])
    return markdown_table(['part'] + ['%s %%' % p for p in profiles], rows)
