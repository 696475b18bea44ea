"""A task connection closed under its subscriber: the selected server's TCP connection to
a robot's task publisher is destroyed (``ss -K``, both ends reset) while the fleet runs.
rospy's subscriber drops a connection that ends and does not connect again by itself, so
the server would never hear that robot's tasks again. The robot sees that a server that
answers its probes does not hear its task topic, and makes the publisher anew; the master
then has the server connect again. Printed: the seconds until the server hears the robot
again, and the robot's task counts. Asserted: it does, with one line saying so, and every
task is reported once. In the fleet profile the manager's connections to the robot are
then reset the same way: the robot, whose rankings the manager (up) no longer hears,
publishes them anew, and the manager connects again; and so are the robot's connections to
its server's results: the server, whose result publisher the probing robot no longer
hears, makes it anew. Each renewal leaves no descriptor behind: the robot's and the
server's epoll descriptors (rospy makes one per topic) are as many after the cuts as
before."""

import subprocess
import time
import xmlrpc.client

import pytest
import rosgraph
import rospy

from server_select.core.config import names
from server_select.core.util.procs import epoll_descriptors as epolls, wait_until
from server_select.msg import SortTask
from server_select.ros.graph import subscribers
from server_select.ros.routing import DEAF_GRACE

from support.fleet import Fleet
from test_faults import STABLE, TASK_TIMEOUT, current_server, show, warm_up

# s after a cut by which the robot has made a deaf connection anew: it sees the deafness at
# a probe answer of that server (1 s apart at most, in either profile), and acts at the
# first answer once DEAF_GRACE s of it have passed
ROBOT_ACTS_BY = DEAF_GRACE + 2.0

ROBOT = 1


def _api(node='/robot%d' % ROBOT):
    return xmlrpc.client.ServerProxy(rosgraph.Master(rospy.get_name()).lookupNode(node))


def hearers(topic, node='/robot%d' % ROBOT, direction='o'):
    """The nodes ``node`` (robot ROBOT) is connected to on ``topic`` (its bus info):
    subscribers of its publisher (``o``: their names), or publishers it hears (``i``: their
    XML-RPC URIs)."""
    try:
        _, _, connections = _api(node).getBusInfo(rospy.get_name())
    except (OSError, rosgraph.MasterError, xmlrpc.client.Error):
        return set()
    return set(c[1] for c in connections if c[4] == topic and c[2] == direction)


def started(nodes):
    """Whether each of ``nodes`` has started all it makes: its last topic, the master
    watch's subscription to ``master_pid``, is made after the node's own start (which, under
    load, can end after its first tasks were answered)."""
    return set(nodes) <= subscribers('/' + names.MASTER_PID_TOPIC, rospy.get_name())


def heard_again(node, topic, cut, connected=10.0, hears=None):
    """Once ``node`` hears robot ROBOT's ``topic``, ``cut()`` its connections (returns how
    many); then ``(how many, whether the robot saw them drop, seconds until ``node`` heard
    it again, None: not within 4 x DEAF_GRACE)``. ``hears()``: the nodes connected (default:
    to robot ROBOT's publisher of ``topic``)."""
    hears = hears or (lambda: hearers(topic))
    assert wait_until(lambda: node in hears(), connected), hears()
    count = cut()
    t_cut = time.monotonic()
    dropped = wait_until(lambda: node not in hears(), 10.0, period=0.1)
    again = wait_until(lambda: node in hears(), 4 * DEAF_GRACE, period=0.2)
    return count, dropped, time.monotonic() - t_cut if again else None


def _close_reports(rec):
    """This node's connections to robot ROBOT's task reports closed here (rospy does not
    make such a connection again); how many."""
    robot_uri = rosgraph.Master(rospy.get_name()).lookupNode('/robot%d' % ROBOT)
    closed = [c for c in list(rec.subs[0].impl.connections) if c.endpoint_id == robot_uri]
    for connection in closed:
        connection.close()
    return len(closed)


def destroy_connections(from_pid, to_node='/robot%d' % ROBOT, topic=names.TASK_REPORT_TOPIC):
    """Reset every TCP connection of process ``from_pid`` to the TCPROS port of ``to_node``
    (which publishes ``topic``); how many there were."""
    _, _, (_, _, port) = _api(to_node).requestTopic(rospy.get_name(), '/' + topic, [['TCPROS']])
    lines = subprocess.run(['ss', '-tnpH', 'dport = :%d' % port], capture_output=True,
                           text=True, check=True).stdout.splitlines()
    local = [line.split()[3] for line in lines if 'pid=%d,' % from_pid in line]
    for address in local:
        subprocess.run(['ss', '-K', '-tn', 'src', address, 'dport', '=', ':%d' % port],
                       capture_output=True, check=True)
    return len(local)


@pytest.mark.parametrize('profile', ['paper', 'fleet'])
def test_a_server_whose_task_connection_was_destroyed_hears_the_robot_again(ros, profile):
    rec = ros['rec']
    rec.clear()
    args = STABLE if profile == 'paper' else {'task_rate': STABLE['task_rate']}
    with Fleet(ros['log'], profile=profile, **args) as fleet:
        warm_up(rec)
        server = current_server(rec, ROBOT)
        node = '/server%d' % server
        topic = '/' + (names.server_topic(server, 'data') if profile == 'fleet' else 'data')
        pids = [fleet.pid(n) for n in ('/robot%d' % ROBOT, node)]
        # counted once both have made every topic (before: once in 3 runs under load, the
        # robot's master watch subscribed after this count: 12 -> 13)
        assert wait_until(lambda: started(['/robot%d' % ROBOT, node]), 20.0)
        epolls_before = [epolls(pid) for pid in pids]
        # this node records the server's task topic too, as `rosbag record` would: the
        # robot must still see that the server itself does not hear it (before: a
        # recorder's connection hid that, and a soak's robot sent into the void for 8 min)
        recorder = rospy.Subscriber(topic, SortTask, lambda _msg: None, queue_size=1) \
            if profile == 'fleet' else None
        assert recorder is None or wait_until(
            lambda: rospy.get_name() in hearers(topic), 10.0), hearers(topic)
        destroyed, dropped, t_again = heard_again(
            node, topic, lambda: destroy_connections(fleet.pid(node)))
        if recorder is not None:
            recorder.unregister()
        again = t_again is not None
        said = wait_until(lambda: rec.log_lines('/robot%d' % ROBOT, 'connecting anew'), 5.0)
        rankings = _cut_rankings(fleet, rec) if profile == 'fleet' else None
        results = _cut_results(fleet, rec) if profile == 'fleet' else None
        outcomes = rec.outcomes((ROBOT,), TASK_TIMEOUT)[ROBOT]
        epolls_after = [epolls(pid) for pid in pids]
    show('%s profile: server %d\'s connections to robot %d destroyed:' % (
        profile, server, ROBOT), [{
            'connections reset': destroyed, 'robot saw it drop': dropped,
            'server hears the robot again after s': '%.1f' % t_again if again else 'never',
            'line': (rec.log_lines('/robot%d' % ROBOT, 'connecting anew') or ['none'])[0],
            'epoll descriptors of robot, server before': epolls_before,
            'after': epolls_after}, outcomes])
    assert destroyed >= 1 and dropped
    assert again, 'server %d never heard robot %d\'s tasks again' % (server, ROBOT)
    # the robot's line when it made the connection anew; none when rospy's own reconnection
    # of the server's subscriber came first (in CI: after 4.2 s, and once 5.35 s)
    assert said or t_again < ROBOT_ACTS_BY, t_again
    assert (outcomes['never answered'], outcomes['duplicates']) == (0, 0), outcomes
    # before the renewals closed the old topic's poller, one more for each: robot 15 -> 17
    kept = all(a <= b for a, b in zip(epolls_after, epolls_before))
    assert kept, (epolls_before, epolls_after)
    if rankings is not None:
        show('the manager\'s connections to robot %d destroyed:' % ROBOT, [rankings])
        assert rankings['connections reset'] >= 1 and rankings['robot saw it drop']
        assert rankings['manager hears the robot again after s'] != 'never', rankings
        assert rankings['line'] != 'none' or rankings['again'] < ROBOT_ACTS_BY, rankings
        show('robot %d\'s connections to server %d reset:' % (ROBOT, results['server']),
             [results])
        assert results['connections reset'] >= 1 and results['robot saw it drop']
        # before servers watched for it: never (20 s waited)
        assert results['robot hears its results again after s'] != 'never', results


def _cut_results(fleet, rec):
    """Robot ROBOT's connections to its server's TCPROS port (its results there, its
    probes) reset. rospy's subscriber does not connect again, so the server's results for
    it would go nowhere while its probes are answered (tasks unanswered for minutes, as
    after a link outage): the server, hearing probes from a robot whose node has not been
    connected to its result publisher for DEAF_GRACE s, makes it anew."""
    server = current_server(rec, ROBOT)
    node, topic = '/server%d' % server, names.robot_topic(ROBOT, names.SORT_RESULT_TOPIC)
    uri = rosgraph.Master(rospy.get_name()).lookupNode(node)
    destroyed, dropped, t_again = heard_again(
        uri, '/' + topic, lambda: destroy_connections(fleet.pid('/robot%d' % ROBOT), node,
                                                      topic),
        hears=lambda: hearers('/' + topic, direction='i'))
    wait_until(lambda: rec.log_lines(node, 'do not reach'), 5.0)
    return {'server': server, 'connections reset': destroyed, 'robot saw it drop': dropped,
            'robot hears its results again after s': 'never' if t_again is None
            else '%.1f' % t_again,
            'line': (rec.log_lines(node, 'do not reach') or ['none'])[0]}


def _cut_rankings(fleet, rec):
    """The manager's connections to robot ROBOT reset: whether, and how soon, it hears the
    robot's rankings again (a manager that does not is never told where its tasks go)."""
    topic, node = '/' + names.RANKINGS_TOPIC, '/manager'
    destroyed, dropped, t_again = heard_again(
        node, topic, lambda: destroy_connections(fleet.pid(node)))
    wait_until(lambda: rec.log_lines('/robot%d' % ROBOT, 'publishing them anew'), 5.0)
    return {'connections reset': destroyed, 'robot saw it drop': dropped,
            'manager hears the robot again after s': 'never' if t_again is None
            else '%.1f' % t_again, 'again': t_again if t_again is not None else 1e9,
            'line': (rec.log_lines('/robot%d' % ROBOT, 'publishing them anew') or ['none'])[0]}


def test_a_report_listener_that_lost_its_connection_hears_the_robot_again(ros):
    """The report listener (this test node) drops its connection to robot ROBOT's task
    reports while the robot waits to start, and, as rospy's subscriber does with a
    connection lost as it was made, never makes it again: the robot, whose first task
    waits until every listener hears its reports, makes the publisher anew and the master
    has the listener connect again. Printed: the seconds until it hears the robot again,
    and the robot's line."""
    rec = ros['rec']
    rec.clear()
    topic, me = '/' + names.TASK_REPORT_TOPIC, rospy.get_name()
    with Fleet(ros['log'], profile='fleet', start_delay=25):
        # every robot's publisher known first: a master's update of the topic's publishers
        # has rospy connect to each again, which would mend the cut by itself
        master = rosgraph.Master(me)
        robots = set(master.lookupNode('/robot%d' % r) for r in (1, 2))
        assert wait_until(lambda: robots <= set(
            c.endpoint_id for c in list(rec.subs[0].impl.connections)), 20.0)
        closed, dropped, t_again = heard_again(me, topic, lambda: _close_reports(rec), 20.0)
        again = t_again is not None
        # the robot's line, shown below, comes over /rosout and was not heard here in 2
        # runs of 7 although the reports were: hearing them again is what is asserted
        wait_until(lambda: rec.log_lines('/robot%d' % ROBOT, 'publishing them anew'), 15.0)
        started = wait_until(lambda: rec.of(rec.reports, ROBOT), 40.0)
    show('this node\'s connection to robot %d\'s task reports closed:' % ROBOT, [{
        'connections closed': closed, 'robot saw it drop': dropped,
        'heard again after s': '%.1f' % t_again if again else 'never',
        'line': (rec.log_lines('/robot%d' % ROBOT, 'publishing them anew') or ['none'])[0],
        'reports heard': len(rec.of(rec.reports, ROBOT))}])
    assert closed == 1 and dropped
    assert again, 'this node never heard robot %d\'s task reports again' % ROBOT
    assert started, 'robot %d never started its tasks' % ROBOT
