"""What the simulator takes from the testbed, measured (no rospy): ``config/sim/model.yaml``.

- ``kinds``: each task kind's CPU seconds on one core of this machine, a log-normal
  (``median_ms``, ``sigma``) fitted to real tasks run here (``--measure``: a sort task's
  message in, sorted, out; a camera frame's decoding and Haar detection); a sort task of
  another size scales with its values (``per`` values); ``warm_ms``: the CPU a server
  spends loading what a kind needs before its first task (OpenCV and a detector for
  frames, timed in a fresh interpreter), which it starts when a probe first announces
  the kind.
- ``hop_ms``: the middleware's delay per message on the testbed beyond the link's own
  (rospy's serialising and threads, the link emulator): calibrated so that the oracle's
  mean round trip matches the testbed's (docs/league.md, "Calibration").
- ``probe_ms``: a probe answer's CPU at the server (the LatencyProbe handler and its load
  report).
- ``cpu_factor``: how much longer CPU work takes on the testbed than timed alone (its
  nodes, emulator and recorder share two cores): calibrated on the capacity cases.
- ``shared_ms``: what a task's work gains on a host whose CPU the fleet's nodes share, as
  against timed alone: a delay of its own per task, exponential with this mean (the
  scheduler's and the interpreter's waits, whatever the task's size; a server's check,
  which reruns a task, draws its own): fitted to the spread of the work servers report on
  the loopback demo (``sim.work_noise``).

``python3 -m server_select.sim.model --measure`` times the kinds here and rewrites
``kinds`` (the constants it keeps).
"""

import argparse
import math
import statistics
import sys
import time

import yaml

from server_select.ros.paths import package_file

PATH = ('config', 'sim', 'model.yaml')


class Model(object):
    """The model's constants, and a task's work drawn from its kind's distribution."""

    def __init__(self, data):
        self.hop = float(data['hop_ms']) * 1e-3
        self.probe_cpu = float(data['probe_ms']) * 1e-3
        self.cpu_factor = float(data.get('cpu_factor', 1.0))
        self.shared = float(data.get('shared_ms', 0.0)) * 1e-3
        self.kinds = dict((name, (float(k['median_ms']) * 1e-3, float(k['sigma']),
                                  int(k.get('per', 0))))
                          for name, k in data['kinds'].items())
        self.warm = dict((name, float(k.get('warm_ms', 0.0)) * 1e-3)
                         for name, k in data['kinds'].items())

    @classmethod
    def load(cls, path=None):
        with open(path or package_file(*PATH)) as stream:
            return cls(yaml.safe_load(stream))

    def alone(self, kind, rng, size=0):
        """CPU seconds of one ``kind`` task timed alone: what its content takes."""
        median, sigma, per = self.kinds[kind]
        median *= self.cpu_factor
        if per and size:
            median *= size / float(per)
        return median * math.exp(rng.gauss(0.0, sigma)) if sigma > 0 else median

    def shared_delay(self, rng):
        """What one task's run gains on a host the fleet's nodes share (0.0 without
        ``shared_ms``): each run's own, a rerun of the same task included."""
        return rng.expovariate(1.0 / self.shared) if self.shared > 0 else 0.0


def _fit(seconds):
    logs = [math.log(s) for s in seconds]
    return {'median_ms': round(1e3 * statistics.median(seconds), 4),
            'sigma': round(statistics.pstdev(logs), 3)}


def measure(repeats=200):
    """``{kind: {median_ms, sigma, ...}}`` timed here (needs the built messages, OpenCV)."""
    import random
    from server_select.bench.capacity_work import cpu_per_task, sort_message
    from server_select.core.flow.sort_kernel import make_values
    from server_select.msg import SortTask
    import io
    values = make_values(random.Random(1), 1000)
    buff = io.BytesIO()
    SortTask(data=values).serialize(buff)
    raw = buff.getvalue()
    times = []
    for _ in range(repeats):
        start = time.process_time()
        sort_message(raw)
        times.append(max(1e-7, time.process_time() - start))
    kinds = {'sort': dict(_fit(times), per=1000)}
    frames = [cpu_per_task('image', repeats=1) for _ in range(max(10, repeats // 10))]
    kinds['image'] = dict(_fit(frames), warm_ms=round(1e3 * statistics.median(
        _warm_image() for _ in range(5)), 1))
    return kinds


def _warm_image():
    """CPU seconds a fresh interpreter takes to load OpenCV and build a detector."""
    import subprocess
    code = ('import time\nt = time.process_time()\nimport cv2\n'
            'from server_select.vision.detection import Detector\nDetector().load()\n'
            'print(time.process_time() - t)')
    return float(subprocess.run([sys.executable, '-c', code], stdout=subprocess.PIPE,
                                universal_newlines=True, check=True).stdout)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--measure', action='store_true', help='time the kinds here and '
                        'rewrite their lines of the model file')
    parser.add_argument('--repeats', type=int, default=200)
    args = parser.parse_args(argv)
    path = package_file(*PATH)
    with open(path) as stream:
        text = stream.read()
    if args.measure:
        data = yaml.safe_load(text)
        data['kinds'] = measure(args.repeats)
        head = ''.join(line for line in text.splitlines(True) if line.startswith('#'))
        with open(path, 'w') as stream:
            stream.write(head + yaml.safe_dump(data, sort_keys=False))
    print(open(path).read())
    return 0


if __name__ == '__main__':
    sys.exit(main())
