"""The fleet demo on one host, measured: 3 identical servers and 2 robots under one
roscore (``demo.launch profile:=fleet``), ``--runs`` times. Per run: switches a minute
per robot over the whole run (the demo's own summary) and once settled (the moves the
robots' rankings show from ``measure_from`` of ``config/sim/loopback.yaml`` on, the part
the simulator measures: what calibration compares), the margin each move's reason gives,
the spread of the robots' probe round trips (the median over robot-server pairs of their
median absolute deviation, which ``config/sim/loopback.yaml``'s link jitter is fitted to),
and the work per sort task each server reports to an observer's probes (robot 0, 2 a
second): its spread from answer to answer is the noise of the work term on a shared CPU,
which the simulator's ``shared_ms`` is fitted to (``python3 -m server_select.sim.work_noise
loopback_demo.json``).

``python3 -m server_select.bench.loopback_demo --runs 3 --seconds 90`` writes
``loopback_demo.json`` and prints a line per run and the median (min-max) over runs.
"""

import json
import math
import os
import re
import statistics
import subprocess
import sys
import threading
import time

from server_select.bench import cli
from server_select.bench.harness import Roscore
from server_select.core.config import names
from server_select.core.util.procs import stop_group
from server_select.core.util.stats import median_deviation
from server_select.core.util.tables import median_range

MARGIN = re.compile(r'faster than \d+ by (-?[0-9.e+-]+) ms')
PROBE_PERIOD = 0.5      # s between an observer's probes of one server


def log_spread(values):
    """The standard deviation of the logarithms of the positive ``values`` (None for fewer
    than 3): a relative spread, as the model's sigma is."""
    logs = [math.log(v) for v in values if v > 0]
    if len(logs) < 3:
        return None
    mean = math.fsum(logs) / len(logs)
    return math.sqrt(math.fsum((x - mean) ** 2 for x in logs) / (len(logs) - 1))


class Observer(object):
    """This process's view of a running demo: the robots' rankings (where each robot's
    tasks go and why) and its own probes' work reports per server."""

    def __init__(self, servers):
        import rospy
        from server_select.msg import LatencySamples, RobotRanking
        self.rospy, self.servers = rospy, servers
        self.lock = threading.Lock()
        self.selected = {}      # robot -> server its tasks go to now
        self.first = {}         # robot -> when its first ranking came (time.monotonic)
        self.moves = []         # (robot, server, reason, s since its first ranking)
        self.work = dict((s, []) for s in servers)   # server -> reported sort work, s
        self.rtts = {}          # (robot, server) -> the robot's probe round trips, s
        self.subs = [rospy.Subscriber('/' + names.RANKINGS_TOPIC, RobotRanking,
                                      self.on_ranking, queue_size=100),
                     rospy.Subscriber('/' + names.SAMPLES_TOPIC, LatencySamples,
                                      self.on_samples, queue_size=100)]
        self.stopped = threading.Event()
        self.thread = threading.Thread(target=self.probe_loop, daemon=True)
        self.thread.start()

    def on_ranking(self, msg):
        with self.lock:
            since = time.monotonic() - self.first.setdefault(msg.robot_id, time.monotonic())
            before = self.selected.get(msg.robot_id)
            if msg.selected and before is not None and msg.selected != before:
                self.moves.append((msg.robot_id, msg.selected, msg.reason, since))
            if msg.selected:
                self.selected[msg.robot_id] = msg.selected

    def on_samples(self, msg):
        with self.lock:
            for server, ok, rtt in zip(msg.server_id, msg.ok, msg.rtt):
                if ok:
                    self.rtts.setdefault((msg.robot_id, server), []).append(rtt)

    def probe_loop(self):
        from server_select.srv import LatencyProbe, LatencyProbeRequest
        proxies = dict((s, self.rospy.ServiceProxy('/' + names.probe_service(s), LatencyProbe))
                       for s in self.servers)
        while not self.stopped.wait(PROBE_PERIOD):
            for server, proxy in proxies.items():
                try:
                    answer = proxy(LatencyProbeRequest(robot_id=0))
                except (self.rospy.ServiceException, OSError):
                    continue        # not up yet, or the demo is ending
                work = dict(zip(answer.kinds, answer.service_time)).get('sort')
                if work:
                    with self.lock:
                        self.work[server].append(work)

    def close(self):
        self.stopped.set()
        for sub in self.subs:
            sub.unregister()
        self.thread.join(5.0)


def probe_spread(series):
    """How far a probe's round trip strays (ms; None: too few): the median over robot-server
    pairs of their round trips' (``series``, s) median absolute deviation, the spread the
    simulator's loopback link jitter is fitted to (``sim.calibration``'s ``probe_mad``)."""
    deviation = median_deviation(series)
    return None if deviation is None else 1e3 * deviation


def settle_time():
    """When the simulator's loopback demo starts to measure (s): what is before it is the
    robots' start, which the calibration leaves out on both sides."""
    from server_select.ros.paths import package_file
    from server_select.sim.run import measured_window
    from server_select.testbed.scenario import Scenario
    return measured_window(Scenario.load(package_file('config', 'sim', 'loopback.yaml')))[0]


def settled(moves, robots, seconds, settle):
    """Switches a minute of each of ``robots`` from ``settle`` s after its first ranking
    to the end of a run of ``seconds`` (``moves``: the Observer's; [] for a shorter run)."""
    if seconds <= settle:
        return []
    return [60.0 * sum(1 for r, _, _, since in moves if r == robot and since >= settle)
            / (seconds - settle) for robot in robots]


def run_once(out, index, seconds, settle, servers=3, robots=2):
    """One demo run of ``seconds``: its figures (a dict; ``settle``: :func:`settle_time`)."""
    summary_path = os.path.join(out, 'summary_%d.json' % index)
    cmd = ['roslaunch', 'server_select', 'demo.launch', 'profile:=fleet', 'output:=log',
           'n_servers:=%d' % servers, 'n_robots:=%d' % robots, 'duration:=%g' % seconds,
           'summary_file:=%s' % summary_path]
    observer = Observer(range(1, servers + 1))
    with open(os.path.join(out, 'launch_%d.log' % index), 'w') as log:
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True)
    try:
        proc.wait(seconds + 120.0)
    finally:
        stop_group(proc, timeout=20.0)
        observer.close()
    with open(summary_path) as stream:
        summary = json.load(stream)
    # a robot the report never heard (0 tasks) would count as 0 switches: left out, named
    per_minute = [60.0 * r['switches'] / seconds for r in summary if r['tasks']]
    unheard = [r['robot'] for r in summary if not r['tasks']]
    margins = [float(m.group(1)) for _, _, why, _ in observer.moves
               for m in [MARGIN.search(why)] if m]
    spreads = dict((s, log_spread(w)) for s, w in observer.work.items())
    return {'switches_per_min': per_minute, 'moves': observer.moves, 'margins_ms': margins,
            'settled_per_min': settled(observer.moves, [r['robot'] for r in summary
                                                        if r['tasks']], seconds, settle),
            'probe_mad_ms': probe_spread(observer.rtts.values()),
            'work_ms': dict((s, 1e3 * sorted(w)[len(w) // 2] if w else None)
                            for s, w in observer.work.items()),
            'work_sigma': spreads, 'tasks': sum(r['tasks'] for r in summary),
            'failed': sum(r['failed'] for r in summary), 'unheard': unheard}


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--runs', type=int, default=3)
    parser.add_argument('--seconds', type=float, default=90.0)
    args = parser.parse_args(argv)
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    runs, settle = [], settle_time()
    with Roscore(out):
        import rospy
        rospy.init_node('loopback_demo_bench', anonymous=True, disable_signals=True)
        for index in range(args.runs):
            run = run_once(out, index, args.seconds, settle)
            runs.append(run)
            sigmas = [v for v in run['work_sigma'].values() if v is not None]
            print('run %d: switches a minute per robot %s (settled %s); %d moves, least margin '
                  '%s ms; probe round trips\' spread %s ms; work sigma per server %s; %d '
                  'tasks, %d failed' % (
                      index + 1, ' '.join('%.1f' % v for v in run['switches_per_min']),
                      ' '.join('%.1f' % v for v in run['settled_per_min']),
                      len(run['moves']), '%.3g' % min(run['margins_ms'])
                      if run['margins_ms'] else '-', '%.3f' % run['probe_mad_ms']
                      if run['probe_mad_ms'] is not None else '-',
                      ' '.join('%.3f' % v for v in sigmas), run['tasks'], run['failed']))
            if run['unheard']:
                print('  the report heard no task of robot %s: left out of the switches'
                      % ', '.join(map(str, run['unheard'])))
            sys.stdout.flush()
    per_minute = [v for r in runs for v in r['switches_per_min']]
    settled_runs = [statistics.mean(r['settled_per_min']) for r in runs if r['settled_per_min']]
    sigmas = [v for r in runs for v in r['work_sigma'].values() if v is not None]
    mads = [r['probe_mad_ms'] for r in runs if r['probe_mad_ms'] is not None]
    print('switches a minute per robot: %s; settled (from %g s), mean over robots per run: %s; '
          'probe round trips\' spread: %s ms; work sigma: %s; moves with a margin <= 0: %d' % (
              median_range(per_minute, '%.2f'), settle,
              median_range(settled_runs, '%.2f') if settled_runs else '-',
              median_range(mads, '%.3f') if mads else '-',
              median_range(sigmas, '%.3f') if sigmas else '-',
              sum(1 for r in runs for m in r['margins_ms'] if m <= 0)))
    cli.write(out, 'loopback_demo.json', {'runs': runs, 'seconds': args.seconds,
                                          'time': time.time()})
    return 0


if __name__ == '__main__':
    sys.exit(main())
