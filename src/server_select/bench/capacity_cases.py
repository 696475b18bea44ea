"""The capacity benchmark's cases and the testbed scenario each makes (no rospy, no
OpenCV): what the testbed benchmark (:mod:`server_select.bench.capacity`) and the simulated
league run alike."""

# The cases of the capacity work, as defaults of the options (an option given wins):
SCENARIOS = {
    # offered load stepping from half to twice the capacity of 3 equal servers
    'overload': dict(shares='0.25,0.25,0.25', robots=6, loads='0.5,1,2'),
    # 10 robots, 4 servers of unequal capacity and distance, at a load they can carry
    'crowd': dict(shares='0.4,0.3,0.2,0.1', delays='5,2,1,0.5', robots=10, loads='0.5'),
    # a server that comes up idle a third of the way in: robots must not all jump to it
    'herd': dict(shares='0.25,0.25,0.25', robots=6, loads='0.5', late=True),
}
TIMEOUT = 5.0        # the task timeout: an answer later than this is not wanted
WARMUP = 8.0         # s of scenario time before the measured part (first tasks answered)
# s after the late server came up (herd), or after every robot's first task report
# (the others), that "settled switches" start
SETTLE = 10.0


def scenario(shares, robots, seconds, delays, late=None):
    """The testbed scenario: ``delays`` one way (ms) from every robot to each server;
    ``late``: the last server starts then (scenario time)."""
    hosts = {'manager': {'role': 'manager'}}
    for index, share in enumerate(shares, start=1):
        hosts['server%d' % index] = {'role': 'server', 'id': index, 'cpu': share}
    if late is not None:
        hosts['server%d' % len(shares)]['start'] = late
    links = {}
    for robot in range(1, robots + 1):
        hosts['robot%d' % robot] = {'role': 'robot', 'id': robot}
        for server, delay in enumerate(delays, start=1):
            links['robot%d server%d' % (robot, server)] = [
                {'at': 0, 'delay': delay, 'jitter': delay / 10.0}]
    return {'name': 'capacity', 'duration': WARMUP + seconds, 'time_zero': 'ready',
            'hosts': hosts, 'default': {'delay': 0.5, 'jitter': 0.05}, 'links': links}
