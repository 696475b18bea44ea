"""A recorded run as a scenario (reads a bag with rosbag; no node): what other rules would
have done on my fleet's run, beside what it did.

From the bag's probe samples (the fleet profile's ``LatencySamples`` batches, or the paper
profile's ``LatencySample`` per pair) and task reports, on any topic, namespaced or not:
- **links**: each robot-server pair's samples; at each good one a step to half its round
  trip less the middleware's part the simulator adds back (``hop_ms`` each way and the
  probe's CPU); from a failed sample to the next good one the link is down;
- **the middleware**: a run on one host has less of it than the testbed: the scenario's
  ``hop_ms`` is the bag's own (half its 5th percentile probe round trip less the probe's
  CPU), at most the model's;
- **servers**: those probed; one whose samples all fail from some time to the end left
  then, one first answering well after the others joined then (no CPU limit: a bag does
  not say a host's share);
- **robots**: the kinds their reports say, each at the run's mean rate a robot, with the
  robots' default task timeout (unknown to a bag);
- **the measured part**: from the first task sent to the end.

:func:`recorded` gives the bag's own figures over that part as the simulator counts them.
"""

import collections
import math

from server_select.core.observe.summary import switch_count
from server_select.core.settings import default
from server_select.core.util.stats import percentile

STEP_MS = 0.05        # a change of the one-way delay smaller than this is no new event
LEFT_AFTER = 3        # failed samples from every robot to the end: the server left
JOINED_AFTER = 5.0    # s after the first sample a server first answered: it joined late


def _events(points, overhead):
    events, last, down = [], None, None
    for t, ok, rtt in sorted(points):
        if not ok:
            if down is not True and events:
                events.append({'at': round(t, 3), 'down': True})
                down = True
            continue
        delay = round(max(0.0, (rtt - overhead) / 2.0) * 1e3, 3)
        if down or last is None or abs(delay - last) >= STEP_MS:
            event = {'at': round(t, 3) if events else 0, 'delay': delay}
            if down or not events:      # (pairs with no samples: down, the default)
                event['down'] = False
            events.append(event)
            last, down = delay, False
    return events


def _server_host(server, samples, first):
    """Server ``server``'s host: when it joined (answered first, if late) and left (the
    first of the failed samples it had from every robot to the end, if enough)."""
    mine = sorted((t, ok) for (_, s), points in samples.items() if s == server
                  for t, ok, _ in points)
    host = {'role': 'server', 'id': server}
    good = [t for t, ok in mine if ok]
    if good and good[0] - first > JOINED_AFTER:
        host['start'] = round(good[0], 3)
    tail = [t for t, ok in mine if not good or t > good[-1]]
    if len(tail) >= LEFT_AFTER:
        host['stop'] = round(max(tail[0], host.get('start', 0.0)), 3)
    return host


def _sent(report, timeout):
    """When the task of ``report`` was sent (s since the bag's start, at least 0)."""
    return max(0.0, report.t - (report.rtt if report.ok else timeout))


def _measured_from(reports):
    sent = [_sent(r, default('task_timeout')) for r in reports]
    return math.floor(1e3 * min(sent)) / 1e3 if sent else 0.0


def scenario(run, model):
    """The scenario mapping of ``run`` (a :func:`server_select.testbed.bag_analysis.load`
    result; ValueError: no probe samples)."""
    samples = collections.defaultdict(list)
    for s in run.samples:
        samples[(s.robot, s.server)].append((s.t, s.ok, s.rtt))
    if not samples:
        raise ValueError('the bag has no probe samples (LatencySamples or LatencySample)')
    rtts = sorted(s.rtt for s in run.samples if s.ok)
    hop = min(model.hop, max(0.0, (percentile(rtts, 5) - model.probe_cpu) / 2.0)) \
        if rtts else model.hop
    overhead = 2.0 * hop + model.probe_cpu
    first = min(s.t for s in run.samples)
    end = max([s.t for s in run.samples] + [r.t for r in run.reports])
    robots = sorted(set(r for r, _ in samples))
    hosts = {'manager': {'role': 'manager'}}
    hosts.update(('server%d' % s, _server_host(s, samples, first))
                 for s in sorted(set(s for _, s in samples)))
    hosts.update(('robot%d' % r, {'role': 'robot', 'id': r}) for r in robots)
    links = dict(('robot%d server%d' % pair, _events(points, overhead))
                 for pair, points in sorted(samples.items()))
    measure_from = _measured_from(run.reports)
    span = max(1.0, end - measure_from)
    kinds = collections.Counter(r.kind for r in run.reports if r.t >= measure_from)

    def rate(kind):
        return round(kinds[kind] / float(len(robots)) / span, 3)
    args = {'task_rate': rate('sort') or 2.0}
    if rate('image') > 0:
        args.update(image_source='frames', frame_rate=rate('image'))
        if not rate('sort'):
            args['sort_tasks'] = False
    return {'name': 'bag', 'duration': round(end + 1e-3, 3), 'hosts': hosts,
            'default': {'delay': 50, 'down': True},
            'links': dict((k, v) for k, v in links.items() if v),
            'suite': {'robot_args': args, 'measure_from': measure_from,
                      'hop_ms': round(1e3 * hop, 3)}}


def recorded(run, measure_from, timeout=None):
    """The bag's own figures over its measured part: ``{tasks, mean, p99, failed,
    switches}`` (s; a failed task at ``timeout``, the robots' default; switches a minute
    per robot, in task order)."""
    timeout = default('task_timeout') if timeout is None else timeout
    mine = [r for r in run.reports if _sent(r, timeout) >= measure_from]
    times = sorted(r.rtt if r.ok else timeout for r in mine)
    by_robot = collections.defaultdict(list)
    for r in mine:
        by_robot[r.robot].append((r.task, r.server, r.kind))
    end = max([r.t for r in run.reports] + [s.t for s in run.samples])
    minutes = max(1e-9, end - measure_from) / 60.0
    return {'tasks': len(mine), 'mean': sum(times) / len(times) if times else None,
            'p99': percentile(times, 99) if times else None,
            'failed': sum(1 for r in mine if not r.ok),
            'switches': sum(switch_count([s for _, s, _ in sorted(t)],
                                         [k for _, _, k in sorted(t)])
                            for t in by_robot.values()) / minutes / max(1, len(by_robot))}
