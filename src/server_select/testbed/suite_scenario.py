"""The scenario suite's scenarios: the files, a copy of every robot per variant, and the
arguments their nodes take (no rospy)."""

import json
import os
import tempfile
import xml.etree.ElementTree as ElementTree

from server_select.core.settings import default
from server_select.ros.paths import package_file
from server_select.testbed.scenario import ScenarioError

FRAMES = os.path.join(tempfile.gettempdir(), 'server_select_frames')   # image_source: frames
REPLICA = 10        # robot r of variant k is robot REPLICA * k + r
# the suite's network scenarios that the leagues run (simulated and on the testbed)
NETWORK = ('paper_moving', 'crossing', 'near_equal', 'link_flap', 'loaded_server',
           'hung_server')


def server_args(suite=None):
    """``{parameter: value}`` of a league's servers beyond their defaults, shared by every
    variant (the simulator's alike): the fleet profile's checks of an idle kind, or a
    scenario's ``suite: check_every``."""
    return {'check_every': float((suite or {}).get('check_every',
                                                   default('check_every', 'fleet')))}


def scenario_path(name):
    """The suite's scenario file ``name`` (``paper_moving`` is the paper's experiment; a
    name ending in ``.yaml`` is a file of the caller's)."""
    if name.endswith('.yaml'):
        return os.path.abspath(name)
    if name == 'paper_moving':
        return package_file('config', 'paper_moving.yaml')
    return package_file('config', 'suite', name + '.yaml')


def short_name(name):
    """The folder of scenario ``name`` in the output (a file's name without .yaml)."""
    return os.path.basename(name)[:-len('.yaml')] if name.endswith('.yaml') else name


def replica_id(variant_index, robot_id):
    if not 0 <= robot_id < REPLICA:
        raise ScenarioError('the suite replicates robots with ids 0-%d, not %d'
                            % (REPLICA - 1, robot_id))
    return REPLICA * variant_index + robot_id


def expand(data, variants, hosts=None):
    """The scenario ``data`` (a mapping) with a copy of every robot host and its links per
    variant (index from 1, in ``variants`` order), each made as ``hosts[variant]`` (host
    keys: ``like``, ``cpu``, ``busy``, ...) says; returns (data, {robot id: (variant,
    scenario robot id)})."""
    data = json.loads(json.dumps(data))      # a deep copy
    hosts, hosts_of = data['hosts'], hosts or {}
    robots = [(name, spec) for name, spec in hosts.items() if spec.get('role') == 'robot']
    owners = {}
    for name, _ in robots:
        del hosts[name]
    links = data.get('links') or {}
    for index, variant in enumerate(variants, start=1):
        for name, spec in robots:
            copy = 'r%dv%d' % (spec['id'], index)
            rid = replica_id(index, spec['id'])
            hosts[copy] = dict(spec, id=rid, **(hosts_of.get(variant) or {}))
            owners[rid] = (variant, spec['id'])
            for key, events in list(links.items()):
                pair = str(key).replace(',', ' ').replace('-', ' ').split()
                if name in pair:
                    other = pair[1] if pair[0] == name else pair[0]
                    links['%s %s' % (copy, other)] = events
    data['links'] = dict((k, v) for k, v in links.items()
                         if not any(n in k.split() for n, _ in robots))
    data['name'] = data.get('name', 'scenario')
    return data, owners


def scenario_robot_args(args, t0):
    """A scenario's ``suite: robot_args`` for its robots: a ``search:`` area of this
    package made a path, ``image_source: frames`` a folder of one camera frame (the
    capacity benchmark's), the sweep started at the scenario's time zero ``t0``."""
    if not args:
        return {}
    args = dict(args, sweep_start='%.6f' % t0)
    source = str(args.get('image_source', ''))
    if source == 'frames':      # the simulator's camera: the capacity benchmark's frame
        from server_select.vision.image_source import write_frame
        write_frame(FRAMES)
        args['image_source'] = FRAMES
    if source.startswith('search:') and not os.path.isabs(source[len('search:'):]):
        args['image_source'] = 'search:' + package_file(source[len('search:'):])
    return args


def robot_params(variant_params, options, scenario_args):
    """A suite robot's parameters: its variant's, the run's task rate, timeout and start
    delay, and then the scenario's own ``robot_args`` (``scenario_robot_args``), which
    win: a scenario that says its robots send 5 tasks a second means it."""
    params = dict(variant_params, task_rate=options.task_rate,
                  task_timeout=options.task_timeout, start_delay=options.start_delay)
    params.update(scenario_args)
    return params


def launch_args(name):
    """The arguments launch file ``name`` declares."""
    root = ElementTree.parse(package_file('launch', name)).getroot()
    return set(arg.get('name') for arg in root.iter('arg'))
