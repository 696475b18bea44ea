"""Every subscriber and service callback of the nodes, fed generated messages.

The server, manager and robot objects are built in this process (their parameters are
this test node's private parameters) and started, so that their callbacks run with real
publishers; hypothesis then calls each callback with arbitrary messages, from arbitrary
publishers. No exception may escape, and afterwards each node still serves a good input.
"""

import io
import math
import os
import time

import numpy as np
import pytest
import rospy
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rospy.impl.registration import Registration, get_service_manager, get_topic_manager
from sensor_msgs.msg import CompressedImage, Image, RegionOfInterest

from server_select.core.util.procs import wait_until
from server_select.msg import (Detection, Detections, FoundTarget, ImageResult, ImageTask,
                               LatencySample, LatencySamples, OrbTask, RobotRanking,
                               SelectionFlag, ServerAnnouncement, SortResult, SortTask)
from server_select.nodes.manager import ManagerNode
from server_select.nodes.robot import RobotNode
from server_select.nodes.server import ServerNode
from server_select.ros.camera import TopicSource
from server_select.ros.membership import ServerRegistry
from server_select.ros.plugins import PluginHandler
from server_select.ros.endpoints import ResultRoutes
from server_select.ros.server_work import ServerWork
from server_select.tasks.orb import Orb
from server_select.vision.image_codec import encode, from_array
from server_select.vision.search import sample_image
from server_select.srv import KnownTargetsRequest, LatencyProbeRequest

FUZZ = settings(max_examples=150, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])
uint32 = st.one_of(st.integers(0, 5), st.integers(0, 2 ** 32 - 1))
int32 = st.one_of(st.integers(-2, 5), st.integers(-2 ** 31, 2 ** 31 - 1))
floats = st.floats(allow_nan=True, allow_infinity=True)
# /fault_tests: this process, which serves latency_S1 and so passes the robot's check
senders = st.sampled_from(['/manager', '/robot1', '/fault_tests', '/spoofer', ''])
text = st.text(max_size=20)
AREA = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'search_small.yaml')


def _serialized(msg):
    buffer = io.BytesIO()
    msg.serialize(buffer)
    return buffer.getvalue()


def sent_by(msg, sender):
    msg._connection_header = {'callerid': sender} if sender else {}
    return msg


_PHOTO = sample_image('coffee.png')[:64, :64]
CAMERA_JPEG_DATA = encode(_PHOTO)[1]
CAMERA_JPEG = _serialized(CompressedImage(format='jpeg', data=CAMERA_JPEG_DATA))
CAMERA_RAW = _serialized(Image(**dict(zip(('encoding', 'height', 'width', 'step', 'data'),
                                          from_array(_PHOTO)))))


def registrations():
    """This process's topic registrations (``{(PUB or SUB, topic): references}``) and
    services, as rospy keeps them."""
    manager = get_topic_manager()
    with manager.lock:
        counts = dict(((Registration.PUB, n), i.ref_count) for n, i in manager.pubs.items())
        counts.update(((Registration.SUB, n), i.ref_count) for n, i in manager.subs.items())
    return counts, set(name for name, _ in get_service_manager().get_services())


def release_since(before):
    """Unregister what this process registered since ``before`` (:func:`registrations`):
    the nodes built here are this process, /fault_tests. Left registered, server 1's
    probe service and the manager's flags stayed /fault_tests's for the session, and a
    later test's fleet, whose master restarted, took them for its own servers' and
    manager's."""
    counts, services = before
    now_counts, now_services = registrations()
    for (kind, topic), count in now_counts.items():
        for _ in range(count - counts.get((kind, topic), 0)):
            get_topic_manager().release_impl(kind, topic)
    for name in now_services - services:
        get_service_manager().get_service(name).shutdown('the fuzz tests are over')


@pytest.fixture(scope='module')
def nodes(ros):
    before = registrations()
    for name, value in {'server_id': 1, 'robot_id': 1, 'robots': '1,2', 'servers': '1,2',
                        'max_task_len': 2000, 'image_source': 'search:' + AREA,
                        'frame_rate': 1.0, 'task_rate': 1.0, 'tasks': 1}.items():
        rospy.set_param('~' + name, value)
    built = {'server': ServerNode(), 'manager': ManagerNode(), 'robot': RobotNode()}
    for node in built.values():
        node.start()
    # the robot's one task of each kind ended before any count is read: the server tests
    # count what server 1 worked on, and a task of this robot's would count as theirs
    assert wait_until(lambda: all(s.flow.sent >= 1 and not len(s.flow)
                                  for s in built['robot'].streams), 30.0)
    yield built
    built['robot'].on_shutdown()       # its timers, streams and prober
    for timer in built['manager'].timers:
        timer.shutdown()
    built['server'].on_shutdown()      # its announcements (it leaves), timers and workers
    release_since(before)


@FUZZ
@given(robot=uint32, task=uint32, server=st.one_of(st.sampled_from([1, 2]), int32),
       data=st.lists(int32, max_size=2500), sender=senders)
def test_server_sort_tasks(nodes, robot, task, server, data, sender):
    """Through the server's routing: a task for server 1 is worked on (done or rejected)
    exactly once, any other is left alone."""
    handler = nodes['server'].handler('sort')
    before = handler.done + handler.rejected
    handler.endpoint.on_task(sent_by(SortTask(
        robot_id=robot, task_id=task, server_id=server, data=np.asarray(data, np.int32)),
        sender), False)
    expected = before + (1 if server == 1 else 0)
    assert wait_until(lambda: handler.done + handler.rejected >= expected, 10.0, period=0.001)
    assert handler.done + handler.rejected == expected


@FUZZ
@given(robot=uint32, server=st.sampled_from([1, 2]), encoding=st.one_of(
    st.sampled_from(['bgr8', 'rgb8', 'mono8', 'bgra8', '16UC1']), text),
    height=st.integers(0, 64), width=st.integers(0, 64), step=st.integers(0, 300),
    data=st.binary(max_size=4000))
def test_server_image_tasks(nodes, robot, server, encoding, height, width, step, data):
    """Through the server's routing: a frame for server 1 is worked on (detected or
    rejected) exactly once, one for server 2 left alone."""
    handler = nodes['server'].handler('image')
    before = handler.done + handler.rejected
    handler.endpoint.on_task(sent_by(ImageTask(
        robot_id=robot, task_id=1, server_id=server, image=Image(
            height=height, width=width, encoding=encoding, step=step, data=data)),
        '/robot1'), False)
    expected = before + (1 if server == 1 else 0)
    assert wait_until(lambda: handler.done + handler.rejected >= expected, 10.0, period=0.001)
    assert handler.done + handler.rejected == expected


@FUZZ
@given(robot=uint32, seq=uint32)
def test_server_probe_service(nodes, robot, seq):
    answer = nodes['server'].on_probe(LatencyProbeRequest(robot_id=robot, seq=seq))
    assert (answer.server_id, answer.seq) == (1, seq)


@FUZZ
@given(claim=st.one_of(st.none(), st.tuples(uint32, uint32)),
       pair=st.sampled_from([(1, 1), (1, 2), (2, 1), (2, 2)]), ok=st.booleans(), rtt=floats,
       sender=st.one_of(st.none(), senders))
def test_manager_samples(nodes, claim, pair, ok, rtt, sender):
    robot, server = claim or pair           # None: the sample claims its own topic's pair
    sender = sender if sender is not None else '/robot%d' % pair[0]   # None: the robot
    nodes['manager'].intake.on_sample(sent_by(LatencySample(robot_id=robot, server_id=server, ok=ok,
                                                            rtt=rtt), sender), pair)
    window = nodes['manager'].rankings.window
    for means in window.robot_stats(pair[0], [1, 2], rospy.get_time()).values():
        assert means.mean is None or (math.isfinite(means.mean) and means.mean >= 0)


@FUZZ
@given(robot=st.one_of(st.sampled_from([1, 2]), uint32),
       samples=st.lists(st.tuples(st.one_of(st.sampled_from([1, 2]), uint32), st.booleans(),
                                  floats), max_size=6),
       ragged=st.integers(0, 2), sender=st.one_of(st.none(), senders))
def test_manager_sample_batches(nodes, robot, samples, ragged, sender):
    """The fleet profile's batches: any ids, NaN or negative round trips, arrays of
    different lengths, any publisher."""
    servers, oks, rtts = (list(x) for x in zip(*samples)) if samples else ([], [], [])
    oks = oks[:len(oks) - ragged] if ragged == 1 else oks
    rtts = rtts + [0.0] if ragged == 2 else rtts
    batch = LatencySamples(robot_id=robot, server_id=servers, ok=oks, rtt=rtts)
    nodes['manager'].intake.on_batch(sent_by(batch, sender if sender is not None else
                                             '/robot%d' % robot))
    window = nodes['manager'].rankings.window
    for means in window.robot_stats(robot, [1, 2], rospy.get_time()).values():
        assert means.mean is None or (math.isfinite(means.mean) and means.mean >= 0)


@pytest.fixture(scope='module')
def view_manager(nodes):
    """A manager that takes the robots' own rankings (the fleet profile's), and the server
    list it keeps from announcements."""
    rospy.set_param('~sample_stream', 'view')
    try:
        manager = ManagerNode()
    finally:
        rospy.set_param('~sample_stream', 'pair')
    registry = ServerRegistry(0.0, manager.on_leave)
    registry.start()
    yield manager, registry
    registry.shutdown()


@FUZZ
@given(robot=st.one_of(st.sampled_from([1, 2]), uint32),
       entries=st.lists(st.tuples(uint32, floats, floats, uint32), max_size=5),
       waits=st.lists(floats, max_size=6), excluded=st.lists(uint32, max_size=3),
       sender=st.one_of(st.none(), senders))
def test_manager_robot_rankings(view_manager, robot, entries, waits, excluded, sender):
    """A robot's own ranking: any ids (repeated too), NaN, infinite or descending
    latencies, arrays of any length, any publisher."""
    manager, _ = view_manager
    servers, means, errors, counts = (list(x) for x in zip(*entries)) if entries else \
        ([], [], [], [])
    manager.intake.on_view(sent_by(RobotRanking(robot_id=robot, ranking=servers, mean_latency=means,
                                                error=errors, sample_count=counts, wait=waits,
                                                excluded=excluded),
                                   sender if sender is not None else '/robot%d' % robot))
    ranking = manager.rankings.rank(robot, rospy.get_time())
    assert all(math.isfinite(m) and m > 0 for m in ranking.means)
    assert ranking.means == sorted(ranking.means)


@FUZZ
@given(server=uint32, lease=floats, sender=senders)
def test_manager_server_announcements(view_manager, server, lease, sender):
    _, registry = view_manager
    registry.on_announcement(sent_by(ServerAnnouncement(server_id=server, lease=lease), sender))
    registry.on_check(None)
    assert all(isinstance(s, int) for s in registry.leases.members())


@FUZZ
@given(robot=st.sampled_from([1, 2]), server=int32, ranking=st.lists(uint32, max_size=5),
       sender=senders)
def test_robot_flags(nodes, robot, server, ranking, sender):
    robot_node = nodes['robot']
    robot_node.on_flag(sent_by(SelectionFlag(robot_id=robot, server_id=server,
                                             ranking=ranking), sender))
    assert set(robot_node.selection.candidates()) <= {1, 2}


@FUZZ
@given(robot=st.sampled_from([1, 2]), task=uint32, server=int32, ok=st.booleans(),
       error=text, data=st.lists(int32, max_size=50), width=st.integers(0, 8),
       sender=senders, kind=st.sampled_from(['sort', 'image']))
def test_robot_results(nodes, robot, task, server, ok, error, data, width, sender, kind):
    robot_node = nodes['robot']
    if robot == 1 and task % 3 == 0:    # often a task in flight, from a server it went to
        stream = next(s for s in robot_node.streams if s.flow.kind == kind)
        pending = list(stream.flow._pending.values())
        if pending:
            task, server = pending[0].task_id, pending[0].attempts[-1][0]
    if kind == 'sort':
        result = SortResult(robot_id=robot, task_id=task, server_id=server, ok=ok, error=error,
                            data=np.asarray(data, np.int32))
    else:
        result = ImageResult(robot_id=robot, task_id=task, server_id=server, ok=ok,
                             error=error, image=Image(width=width))
    stream = next(s for s in robot_node.streams if s.flow.kind == kind)
    stream.on_result(sent_by(result, sender))
    flow = stream.flow      # each task sent ends once, answered or failed: none twice
    assert wait_until(lambda: flow.ok + flow.failed + len(flow) == flow.sent, 2.0,
                      period=0.001), (flow.sent, flow.ok, flow.failed, len(flow))


@FUZZ
@given(robot=st.sampled_from([1, 2]), task=uint32, boxes=st.lists(
    st.tuples(uint32, uint32, uint32, uint32, text, floats), max_size=4), x=floats, y=floats,
    label=text)
def test_robot_search_callbacks(nodes, robot, task, boxes, x, y, label):
    """Detections of the robot's own frames and targets other robots found: each adds at
    most one known target per box or report, and only at a place (finite coordinates)."""
    search = nodes['robot'].search
    before = len(search.on_known_targets(KnownTargetsRequest()).targets)
    search.on_detections(sent_by(Detections(robot_id=robot, task_id=task, detections=[
        Detection(roi=RegionOfInterest(x_offset=a, y_offset=b, width=c, height=d), label=e,
                  score=f) for a, b, c, d, e, f in boxes]), '/server1'))
    mine = len(search.on_known_targets(KnownTargetsRequest()).targets)
    assert before <= mine <= before + (len(boxes) if robot == 1 else 0)
    search.on_found(sent_by(FoundTarget(robot_id=robot, task_id=task, label=label, x=x, y=y),
                            '/robot2'))
    known = search.on_known_targets(KnownTargetsRequest()).targets
    placed = robot != 1 and math.isfinite(x) and math.isfinite(y)
    assert mine <= len(known) <= mine + placed
    assert all(math.isfinite(t.x) and math.isfinite(t.y) for t in known), known[-3:]


def test_every_node_still_serves(nodes):
    sort = nodes['server'].handler('sort')
    done = sort.done
    result = sort.on_task(SortTask(robot_id=5, task_id=1, server_id=1,
                                   data=np.asarray([3, 1, 2], np.int32)))
    assert result.ok and list(result.data) == [1, 2, 3] and sort.done == done + 1
    manager = nodes['manager']
    manager.intake.on_sample(sent_by(LatencySample(robot_id=1, server_id=1, ok=True, rtt=0.002),
                                     '/robot1'), (1, 1))
    assert manager.rankings.window.stats(1, 1, rospy.get_time()).ok_count >= 1
    robot = nodes['robot']
    robot.on_flag(sent_by(SelectionFlag(robot_id=1, server_id=2, ranking=[2, 1]), '/manager'))
    # the flag's ranking, without the servers the fuzzed results ejected (when none is
    # usable, those whose last probe was answered: the panic rule; a CI run had server 1)
    candidates = robot.selection.candidates()
    assert candidates == robot.health.order([2, 1]), candidates


@FUZZ
@given(kind=st.sampled_from(['sensor_msgs/Image', 'sensor_msgs/CompressedImage',
                             'std_msgs/String', '']),
       buff=st.one_of(st.binary(max_size=200), st.sampled_from([
           b'', CAMERA_JPEG, CAMERA_RAW])))
def test_camera_frames(kind, buff):
    """A camera topic's frames (rospy.AnyMsg): a frame or a ValueError, nothing else."""
    source = TopicSource('/camera')
    msg = rospy.AnyMsg()
    msg._buff, msg._connection_header = buff, {'type': kind}
    source.on_frame(msg)
    try:
        frame, _ = source.frame(0.0)
        assert frame.ndim in (2, 3)
    except ValueError:
        pass
    assert not source.ready()     # each frame is used once


@FUZZ
@given(robot=uint32, server=st.sampled_from([1, 2]), fmt=st.one_of(
    st.sampled_from(['jpeg', 'png', 'bgr8; jpeg compressed bgr8']), text),
    data=st.one_of(st.binary(max_size=300), st.just(CAMERA_JPEG_DATA)),
    features=st.integers(0, 2 ** 32 - 1))
def test_plugin_tasks(nodes, robot, server, fmt, data, features):
    if not hasattr(test_plugin_tasks, 'handler'):    # one handler, its endpoint and workers
        work = ServerWork(1, 2, 100)
        work.start()
        test_plugin_tasks.handler = PluginHandler(1, Orb(None, {}), work.submit)
        test_plugin_tasks.handler.start()
    handler = test_plugin_tasks.handler
    before = handler.done + handler.rejected
    handler.endpoint.on_task(OrbTask(robot_id=robot, task_id=1, server_id=server,
                                     frame=CompressedImage(format=fmt, data=data),
                                     max_features=min(features, 2000)), False)
    expected = before + (1 if server == 1 else 0)
    assert wait_until(lambda: handler.done + handler.rejected >= expected, 10.0, period=0.001)
    assert handler.done + handler.rejected == expected


def test_direct_results_go_to_a_bounded_number_of_robots(ros):
    """Tasks or probes under made-up robot ids cannot make a server open result topics
    without end, nor lock out a robot it has not met: the least recently used goes."""
    routes = ResultRoutes('bounded_results', SortResult, connect_wait=0.0, most=2)
    for robot in (1, 2, 3):
        routes.publish(robot, SortResult())
    assert list(routes.pubs) == [2, 3] and routes.evicted == 1
    routes.publish(2, SortResult())
    routes.publish(1, SortResult())          # robot 1 is back: robot 3 was used longest ago
    assert list(routes.pubs) == [2, 1] and routes.evicted == 2


def test_a_result_waits_for_its_robot_without_holding_the_worker(ros):
    """A reply to a robot with no subscriber yet returns at once; the result goes out when
    the robot connects within ``connect_wait``, and a robot that never does costs nothing
    more (before: the worker waited 1 s for each such reply)."""
    routes = ResultRoutes('held_results', SortResult, connect_wait=5.0)
    start = time.monotonic()
    for task in range(20):
        routes.publish(7, SortResult(task_id=task))
    took = time.monotonic() - start
    got = []
    sub = rospy.Subscriber('/robot_7/held_results', SortResult, lambda m: got.append(m.task_id))
    try:
        arrived = wait_until(lambda: len(got) == 20, 10.0)
    finally:
        sub.unregister()
    print('20 replies to a robot not yet connected: %.1f ms in the worker, %d delivered once '
          'it connected' % (1e3 * took, len(got)))
    assert took < 0.5 and arrived and sorted(got) == list(range(20))
