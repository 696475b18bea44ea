"""Resources of the soak's nodes over time: every ``period`` s each node's RSS, open file
descriptors, threads and CPU seconds from ``/proc`` (:class:`Sampler`), and the slope of
each over the run's second half (:func:`slopes`, pure: a leak shows as a slope, a restart
does not, its samples being compared within each life of the node)."""

import collections
import os
import threading
import time

from server_select.core.util.procs import stat_fields

Sample = collections.namedtuple('Sample', 't node pid rss_mib fds threads cpu_s')
MEASURES = ('rss_mib', 'fds', 'threads', 'cpu_s')
SETTLE = 60.0       # s after a node's start that its samples are not yet steady


def read(pid, node, now):
    """One Sample of process ``pid`` at ``now``, None when it is gone (or a zombie: no
    memory)."""
    try:
        with open('/proc/%d/status' % pid) as stream:
            status = dict(line.split(':', 1) for line in stream if ':' in line)
        fds = len(os.listdir('/proc/%d/fd' % pid))
        fields = stat_fields('/proc/%d/stat' % pid)
        rss = int(status['VmRSS'].split()[0]) / 1024.0
    except (OSError, ValueError, KeyError):
        return None
    ticks = os.sysconf('SC_CLK_TCK')
    cpu = (int(fields[11]) + int(fields[12])) / float(ticks)    # utime + stime
    return Sample(now, node, pid, rss, fds, int(status['Threads']), cpu)


class Sampler(object):
    """Samples ``nodes`` every ``period`` s on a thread of its own; ``pid_of(node)`` asks
    who the node is now (None: the master does not know; the last pid is used while its
    process lives)."""

    def __init__(self, nodes, pid_of, period=10.0, clock=time.time):
        self.nodes, self.pid_of, self.period, self.clock = list(nodes), pid_of, period, clock
        self.samples, self.pids = [], {}
        self.stopping = threading.Event()
        self.thread = threading.Thread(target=self._loop, daemon=True)

    def start(self):
        self.thread.start()
        return self

    def stop(self):
        self.stopping.set()
        self.thread.join(30.0)

    def _loop(self):
        while not self.stopping.is_set():
            self.sample_once()
            self.stopping.wait(self.period)

    def sample_once(self):
        now = self.clock()
        for node in self.nodes:
            try:
                pid = self.pid_of(node)
            except Exception:      # the master's thread timed out: keep the last pid
                pid = None
            pid = pid or self.pids.get(node)
            sample = read(pid, node, now) if pid else None
            if sample is not None:
                self.pids[node] = pid
                self.samples.append(sample)


def slopes(samples, start, end, settle=SETTLE):
    """``{node: {measure: (slope per 10 minutes, samples used)}}`` over ``[start, end]``,
    each life (pid) of a node on its own after ``settle`` s: the pooled within-life
    least-squares slope, so that a restart's drop is no slope. CPU is a rate: its slope is
    that of the CPU share (%% of a core) between samples."""
    lives = collections.defaultdict(list)
    for sample in sorted(samples, key=lambda s: s.t):
        lives[(sample.node, sample.pid)].append(sample)
    result = collections.defaultdict(dict)
    for measure in MEASURES:
        sums = collections.defaultdict(lambda: [0.0, 0.0, 0])
        for (node, _), life in lives.items():
            points = _points(life, measure, life[0].t + settle, start, end)
            if len(points) < 3:
                continue
            mean_t = sum(t for t, _ in points) / len(points)
            mean_v = sum(v for _, v in points) / len(points)
            acc = sums[node]
            acc[0] += sum((t - mean_t) * (v - mean_v) for t, v in points)
            acc[1] += sum((t - mean_t) ** 2 for t, _ in points)
            acc[2] += len(points)
        for node, (sxy, sxx, n) in sums.items():
            result[node][measure] = (sxy / sxx * 600.0 if sxx else 0.0, n)
    return dict(result)


def _points(life, measure, steady, start, end):
    """(t, value) of one life within the window; CPU as the share between samples."""
    if measure != 'cpu_s':
        return [(s.t, getattr(s, measure)) for s in life if s.t >= steady and start <= s.t <= end]
    return [(b.t, 100.0 * (b.cpu_s - a.cpu_s) / (b.t - a.t)) for a, b in zip(life, life[1:])
            if b.t > a.t and a.t >= steady and start <= b.t <= end]
