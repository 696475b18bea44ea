"""A recorded run's links as a scenario (reads a bag with rosbag; no node): what another
rule would have done on my fleet's links.

Each robot-server pair's probe samples in the bag (the fleet profile's ``LatencySamples``
batches, or the paper profile's ``LatencySample`` per pair; any topic, namespaced or
not) become the pair's link: at each good sample a step to half its round trip, less the
middleware's part the model adds back (``hop_ms`` each way, ``probe_ms``); from a failed
sample to the next good one the link is down. Robots send what their task reports say
they sent (sort tasks and frames a second, the run's mean), with the run's task timeout
unknown to the bag (2 s, the robots' default). Servers are the run's, with no CPU limit
(a bag does not say a host's share).
"""

import collections

STEP_MS = 0.05        # a change of the one-way delay smaller than this is no new event


def _samples(bag):
    """``({(robot, server): [(t, ok, rtt)]}, {(robot, kind): tasks}, start, end)``."""
    samples, tasks = collections.defaultdict(list), collections.Counter()
    start, end = bag.get_start_time(), bag.get_end_time()
    for _, msg, stamp in bag.read_messages():
        kind, t = getattr(msg, '_type', ''), stamp.to_sec() - start
        if kind == 'server_select/LatencySamples':
            for server, ok, rtt in zip(msg.server_id, msg.ok, msg.rtt):
                samples[(msg.robot_id, server)].append((t, ok, rtt))
        elif kind == 'server_select/LatencySample':
            samples[(msg.robot_id, msg.server_id)].append((t, msg.ok, msg.rtt))
        elif kind == 'server_select/TaskReport':
            tasks[(msg.robot_id, msg.kind)] += 1
    return samples, tasks, start, end


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
            if down:
                event['down'] = False
            events.append(event)
            last, down = delay, False
    return events


def scenario(path, model):
    """The scenario mapping of the bag at ``path`` (ValueError: no probe samples)."""
    import rosbag
    with rosbag.Bag(path) as bag:
        samples, tasks, start, end = _samples(bag)
    if not samples:
        raise ValueError('%s has no probe samples (LatencySamples or LatencySample)' % path)
    overhead = 2.0 * model.hop + model.probe_cpu
    robots = sorted(set(r for r, _ in samples))
    servers = sorted(set(s for _, s in samples))
    hosts = {'manager': {'role': 'manager'}}
    hosts.update(('server%d' % s, {'role': 'server', 'id': s}) for s in servers)
    hosts.update(('robot%d' % r, {'role': 'robot', 'id': r}) for r in robots)
    links = dict(('robot%d server%d' % pair, _events(points, overhead))
                 for pair, points in sorted(samples.items()))
    span = max(1.0, end - start)

    def rate(kind):
        return sum(n for (_, k), n in tasks.items() if k == kind) / float(len(robots)) / span
    args = {'task_rate': round(rate('sort'), 3) or 2.0}
    if rate('image') > 0:
        args.update(image_source='frames', frame_rate=round(rate('image'), 3))
        if not rate('sort'):
            args['sort_tasks'] = False
    return {'name': 'bag', 'duration': round(span, 3), 'hosts': hosts,
            'default': {'delay': 50, 'down': True},
            'links': dict((k, v) for k, v in links.items() if v),
            'suite': {'robot_args': args, 'measure_from': 0.0}}
