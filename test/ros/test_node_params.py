"""Every node refuses bad parameters with a ParamError naming the parameter, before it
touches the graph: the node classes built against a parameter table of this test (no
master). The launch-level path (one clear line, exit status 2) is bad_input.test's.

The cases are written as ``rosrun`` arguments and read the way rosrun reads them (each
value as YAML), so that a case here is what an operator would type.
"""

import logging
import os

import pytest
import rospy
import yaml
from std_msgs.msg import Empty

from server_select.core.config.params import ParamError
from server_select.core.trust.keys import make_key
from server_select.nodes.manager import ManagerNode
from server_select.nodes.robot import RobotNode
from server_select.nodes.server import ServerNode
from server_select.ros import launch_args, node, params_in_force, seal

NODES = {'robot': RobotNode, 'manager': ManagerNode, 'server': ServerNode}
ROBOT_OK = ['_robot_id:=1', '_servers:=1,2,3']

BAD_PARAMS = [
    ('robot', ROBOT_OK + ['_mode:=random'], "~mode: unknown mode 'random'"),
    ('robot', ['_robot_id:=1', '_servers:=""'], '~servers: expected a non-empty list of ids'),
    ('robot', ['_robot_id:=1', '_servers:=a,b'], '~servers: expected a non-negative integer id'),
    ('robot', ['_robot_id:=1', '_servers:=1,1'], '~servers: duplicate ids [1]'),
    ('robot', ['_servers:=1,2'], '~robot_id: required parameter is not set'),
    ('robot', ROBOT_OK + ['_mode:=fixed', '_fixed_server:=9'],
     '~fixed_server: server 9 is not in servers [1, 2, 3]'),
    ('robot', ROBOT_OK + ['_probe_rate:=0'], '~probe_rate: expected a positive number, got 0'),
    ('robot', ROBOT_OK + ['_task_rate:=-2'], '~task_rate: expected a positive number, got -2'),
    ('robot', ROBOT_OK + ['_task_size:=ten'], '~task_size: expected a positive integer'),
    ('robot', ROBOT_OK + ['_manager_timeout:=0'], '~manager_timeout: expected a positive'),
    ('robot', ROBOT_OK + ['_sort_tasks:=maybe'], '~sort_tasks: expected true or false'),
    ('robot', ROBOT_OK + ['_eject_time:=60'], '~eject_time 60 is longer than ~eject_max 30'),
    ('robot', ROBOT_OK + ['_task_plugins:=no_such_module:Task'],
     "~task_plugins: cannot load 'no_such_module:Task'"),
    ('robot', ROBOT_OK + ['_task_plugins:=server_select.tasks.orb:Orb'],
     '~orb: source: required'),
    ('robot', ROBOT_OK + ['_sort_tasks:=false'], 'no tasks to send'),
    ('robot', ROBOT_OK + ['_image_source:=/no/such/folder'], '~image_source:'),
    ('robot', ROBOT_OK + ['_profile:=fleet', '_dwell:=2', '_eject_time:=2'],
     '~dwell (a setting of policy hysteresis; ~policy least_latency chooses per task); '
     '~eject_time (fixed by least_latency'),
    ('robot', ROBOT_OK + ['_profile:=fleet', '_probe_rate:=8'],
     '~probe_rate (probes are paced by ~contender_rate 4)'),
    ('manager', ['_robots:=1', '_servers:=[]'], '~servers: expected a non-empty list of ids'),
    ('manager', ['_robots:=1', '_servers:=1', '_window:=0'], '~window: expected a positive'),
    ('manager', ['_robots:=1', '_servers:=1', '_robot_node:=robot{nr}'],
     "~robot_node: 'robot{nr}' is not a node name with {id}"),
    ('server', [], '~server_id: required parameter is not set'),
    ('server', ['_server_id:=-3'], '~server_id: ids must be non-negative, got -3'),
    ('server', ['_server_id:=1', '_cascade:=no_such_cascade.xml'], '~detector/~cascade:'),
]


def private_params(args):
    """``{'~name': value}`` of rosrun's ``_name:=value`` arguments, values read as YAML."""
    params = {}
    for arg in args:
        name, _, value = arg.partition(':=')
        params['~' + name[1:]] = yaml.safe_load(value)
    return params


@pytest.fixture
def param_server(monkeypatch):
    """The node's private parameters from a dict; nothing else of the graph is reachable."""
    table = {}
    missing = object()

    def get_param(name, default=missing):
        if name in table:
            return table[name]
        if default is missing:
            raise KeyError(name)
        return default

    monkeypatch.setattr(rospy, 'get_param', get_param)
    monkeypatch.setattr(rospy, 'has_param', lambda name: name in table)
    monkeypatch.setattr(rospy, 'set_param', table.__setitem__)
    monkeypatch.setattr(rospy, 'delete_param', table.__delitem__)
    monkeypatch.setattr(params_in_force, '_WRITTEN', {})
    monkeypatch.setattr(node, '_PROFILE', None)
    monkeypatch.setattr(node, '_FLEET_NS', None)
    monkeypatch.setattr(seal, '_STATE', {})
    return table


@pytest.mark.parametrize('kind, args, message', BAD_PARAMS,
                         ids=['%s %s' % (c[0], ' '.join(c[1])) for c in BAD_PARAMS])
def test_a_bad_parameter_is_refused_by_name(param_server, kind, args, message):
    param_server.update(private_params(args))
    with pytest.raises(ParamError) as error:
        NODES[kind]()
    assert message in str(error.value)


def test_the_cases_are_read_as_rosrun_reads_them():
    assert private_params(['_servers:=1,2,3', '_servers2:=""', '_rate:=0', '_list:=[]',
                           '_on:=false', '_name:=robot{nr}']) == {
        '~servers': '1,2,3', '~servers2': '', '~rate': 0, '~list': [], '~on': False,
        '~name': 'robot{nr}'}


@pytest.mark.parametrize('kind, args', [('robot', ROBOT_OK), ('manager', ['_robots:=1',
                                                                          '_servers:=1'])])
def test_good_parameters_are_accepted(param_server, kind, args):
    """The table is not refusing everything: the same nodes build with good parameters
    (their wiring to the graph starts only in ``start()``)."""
    param_server.update(private_params(args))
    assert NODES[kind]() is not None


def test_the_defaults_a_node_uses_are_written_back(param_server):
    """``rosparam get /robot1/probe_rate`` shows what the robot uses: the profile's
    default, written where the robot looked; a value set is left as it was."""
    param_server.update(private_params(ROBOT_OK + ['_profile:=fleet', '_window:=3']))
    NODES['robot']()
    assert param_server['~contender_rate'] == 4.0 and param_server['~window'] == 3
    assert param_server['~servers'] == '1,2,3'
    assert params_in_force._WRITTEN['contender_rate'] == 4.0
    assert 'window' not in params_in_force._WRITTEN
    # what a fleet robot reads but does not use is not shown (its probes go at
    # ~contender_rate; its rule fixes the ejections and has no ranking policy)
    assert not set(['~probe_rate', '~eject_time', '~dwell', '~fixed_server']) & set(param_server)


def test_a_paper_robot_shows_the_probe_rate_it_uses(param_server):
    param_server.update(private_params(ROBOT_OK))
    NODES['robot']()
    assert param_server['~probe_rate'] == 1.0 and param_server['~eject_time'] == 1.0


def test_an_unknown_private_parameter_is_named_with_the_nearest_known_one(monkeypatch):
    monkeypatch.setattr(rospy, 'get_name', lambda: '/robot1')
    monkeypatch.setattr(rospy, 'get_param_names', lambda: [
        '/robot1/probe_rte', '/robot1/probe_rate', '/robot1/orb/rate', '/robot1/zzz',
        '/robot10/probe_rte', '/robot1/defaults_written/pid', '/rosdistro'])
    monkeypatch.setattr(params_in_force, '_NAMESPACES', {'orb'})
    assert params_in_force.unknown(node.PARAMS) == [('probe_rte', 'probe_rate'),
                                                    ('zzz', None)]


def test_a_fleet_key_that_cannot_be_used_ends_the_node_by_name(param_server, tmp_path):
    """``runner.run`` reads the key before it builds the node (seal.enabled())."""
    path = str(tmp_path / 'fleet.key')
    make_key(path)
    os.chmod(path, 0o644)
    param_server['~fleet_key'] = path
    with pytest.raises(ParamError, match='~fleet_key: fleet key %s can be read or written by '
                       'others .*chmod 600' % path):
        seal.enabled()
    param_server['~fleet_key'] = str(tmp_path / 'missing.key')
    with pytest.raises(ParamError, match='~fleet_key: cannot read fleet key'):
        seal.enabled()


def test_a_second_key_without_a_first_is_refused(param_server, tmp_path):
    path = str(tmp_path / 'next.key')
    make_key(path)
    param_server['~fleet_key_next'] = path
    with pytest.raises(ParamError, match='~fleet_key_next: set ~fleet_key too'):
        seal.enabled()


def test_with_a_key_a_plug_in_whose_result_cannot_carry_a_seal_is_refused(param_server,
                                                                          tmp_path):
    path = str(tmp_path / 'fleet.key')
    make_key(path)
    param_server.update(private_params(ROBOT_OK))
    param_server['~fleet_key'] = path
    seal.announce('/robot1', 'robot')
    assert seal.enabled()
    assert NODES['robot']() is not None          # the built-in task types carry one
    with pytest.raises(ParamError, match="~fleet_key: the result of task type 'x' "
                       r'\(std_msgs/Empty\) has no seal field'):
        seal.require_sealable(Empty, "the result of task type 'x'")


def test_a_node_given_another_roles_key_or_type_is_refused_by_name(param_server, tmp_path):
    """A manager given a robot's key file ends at start naming the key it needs; a robot
    (its role's file) cannot make a publisher of flags, nor a keyed node without a role."""
    from server_select.core.trust.keys import make_role_key
    from server_select.msg import LatencySamples, SelectionFlag
    fleet, robot = str(tmp_path / 'fleet.key'), str(tmp_path / 'robot.key')
    make_key(fleet)
    make_role_key(fleet, 'robot', robot)
    param_server['~fleet_key'] = robot
    with pytest.raises(ParamError, match='signs as robot, and this node publishes as manager: '
                       'give it the manager key'):
        seal.announce('/manager', 'manager')
    seal._STATE.clear()
    seal.announce('/robot1', 'robot')
    assert seal.SealedPublisher('/samples', LatencySamples, queue_size=1) is not None
    with pytest.raises(ParamError, match='signs as the robot role, and only the manager role '
                       'may publish server_select/SelectionFlag'):
        seal.SealedPublisher('/server_select_flag', SelectionFlag, queue_size=1)
    seal._STATE.clear()
    seal.announce('/top', None)                  # a viewer: checks, publishes nothing sealed
    assert seal.enabled()
    with pytest.raises(ParamError, match='signs as no role'):
        seal.SealedPublisher('/samples', LatencySamples, queue_size=1)


def test_a_launch_argument_no_launch_file_declares_is_named_by_the_first_node():
    """``roslaunch server_select demo.launch probe_rat:=5``: roslaunch ignores it; the
    first node of the package it starts (the manager) names it. An argument of an included
    file (robot.launch's ``task_plugins``, through ``pass_all_args``) is declared."""
    first, unknown = launch_args.undeclared(
        ['roslaunch', '--screen', '-p', '11411', 'server_select', 'demo.launch',
         'profile:=fleet', 'probe_rat:=5', 'task_plugins:=a:B', 'xyzzy:=1', '__log:=x'])
    assert first == '/manager'
    assert unknown == [('probe_rat', 'probe_rate'), ('xyzzy', None)]
    first, unknown = launch_args.undeclared(['roslaunch', 'server_select', 'robot.launch',
                                             'robot_id:=2'])
    assert (first, unknown) == ('/robot2', [])


def test_rospys_warning_of_a_connection_abandoned_before_its_header_goes_to_debug():
    """A client that gave up connecting: no WARN in a healthy fleet; a bad header warns."""
    keep = node.AbandonedConnections().filter
    record = logging.LogRecord('rosout', logging.WARNING, __file__, 1,
                               'Inbound TCP/IP connection failed: %s', (
                                   'connection from sender terminated before handshake '
                                   'header received. 0 bytes were received. Please check '
                                   'sender for additional details.',), None)
    assert not keep(record)
    record.args = ('header too long: 40000000 bytes',)
    assert keep(record)
