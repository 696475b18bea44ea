"""Robot: probes every server, follows the manager's selection and sends tasks."""

import concurrent.futures
import itertools
import threading
import time

import rospy
from std_msgs.msg import Header

from server_select import names
from server_select.detection import Detector, DetectorError
from server_select.image_source import SourceError, open_source
from server_select.msg import FoundTarget, LatencySample, SelectionFlag, TaskReport
from server_select.node_util import get_param, run
from server_select.params import (ParamError, parse_fixed_server, parse_id, parse_id_list,
                                  parse_mode, parse_non_negative, parse_positive)
from server_select.probe_client import TimedServiceProxy
from server_select.search import Found, SearchError, TargetRegistry
from server_select.srv import KnownTargets, KnownTargetsResponse, LatencyProbe, LatencyProbeRequest
from server_select.task_streams import ImageStream, SortStream
from server_select.tracker import NONE


class RobotNode(object):
    """A robot of the fleet.

    Probing: every ``1/~probe_rate`` s each server's ``latency_S<s>`` is called over a
    persistent connection, each server from its own worker thread, each call bounded by
    ``~probe_timeout``; a server whose previous probe is still running gets a failed
    sample instead of a second call. Every sample, failed ones too, is published.

    Tasks go to the selected server (``~mode`` ``select``), to ``~fixed_server``
    (``fixed``, the paper's baseline), or are processed by the robot itself (``local``,
    the no-offloading reference). Two streams, each optional: sort tasks (``~task_size``
    random int32 at ``~task_rate``) and camera frames (``~image_source`` at
    ``~frame_rate``). Each task ends in exactly one ``task_report``: a checked result, an
    error result, or a timeout after ``~task_timeout``. Targets detected in the robot's
    frames are recorded once in a registry shared through ``found_targets``: a target
    another robot already found is not reported again.

    :ROS Parameters:
        - ``~robot_id`` (int, required)
        - ``~servers`` (list of int, required): servers to probe.
        - ``~mode`` (str, ``select``): ``select``, ``fixed`` or ``local``.
        - ``~fixed_server`` (int, first of ``~servers``): target in fixed mode.
        - ``~probe_rate`` (Hz, 1.0), ``~probe_timeout`` (s, 0.5)
        - ``~sort_tasks`` (bool, true): send sort tasks.
        - ``~task_rate`` (Hz, 2.0), ``~task_size`` (int, 1000), ``~task_timeout`` (s, 2.0)
        - ``~tasks`` (int, 0): stop each stream after this many tasks (0: never).
        - ``~image_source`` (str, ''): camera frames from a folder, a video file, or
          ``search:<area.yaml>`` (a synthetic search area); empty: no image tasks.
        - ``~frame_rate`` (Hz, 10.0), ``~image_encoding`` (``bgr8``; or ``rgb8``, ``mono8``)
        - ``~robot_index``, ``~robot_count`` (int, 0 and 1): this robot's strip of a search area.
        - ``~speed`` (area pixels/s, 200.0): how fast the robot sweeps its strip.
        - ``~merge_radius`` (area pixels, 150.0): detections this close are one target.
        - ``~detector``, ``~cascade`` (as the server's): used in mode ``local`` only.
        - ``~start_delay`` (s, 0.0): wait this long before the first task, e.g. for a
          recorder (rosbag, a test) to connect: rospy drops messages sent before that.
        - ``~summary_period`` (s, 10.0): period of the log summary.
        - ``~seed`` (int, robot_id): task data random seed.
    :ROS Publishers:
        - ``latency_R<robot_id>S<s>`` (server_select/LatencySample), one topic per server.
        - ``data`` (server_select/SortTask), ``task_image`` (server_select/ImageTask)
        - ``task_report`` (server_select/TaskReport)
        - ``found_targets`` (server_select/FoundTarget)
    :ROS Subscribers:
        - ``server_select_flag`` (server_select/SelectionFlag)
        - ``processed_data`` (server_select/SortResult), ``processed_image``
          (server_select/ImageResult), ``detections`` (server_select/Detections)
        - ``found_targets`` (server_select/FoundTarget)
    :ROS Services:
        - ``~known_targets`` (server_select/KnownTargets): the targets found so far.
    :ROS Services called:
        - ``latency_S<s>`` (server_select/LatencyProbe)
    """

    def __init__(self):
        self.robot_id = parse_id('~robot_id', get_param('~robot_id'))
        self.servers = parse_id_list('~servers', get_param('~servers'))
        self.mode = parse_mode('~mode', get_param('~mode', 'select'))
        self.fixed_server = parse_fixed_server(
            '~fixed_server', get_param('~fixed_server', self.servers[0]), self.servers, self.mode)
        self.probe_rate = parse_positive('~probe_rate', get_param('~probe_rate', 1.0))
        self.probe_timeout = parse_positive('~probe_timeout', get_param('~probe_timeout', 0.5))
        task_timeout = parse_positive('~task_timeout', get_param('~task_timeout', 2.0))
        tasks = get_param('~tasks', 0)
        task_limit = 0 if tasks in (0, '0') else parse_positive('~tasks', tasks, integer=True)
        summary_period = parse_positive('~summary_period', get_param('~summary_period', 10.0))
        seed = parse_id('~seed', get_param('~seed', self.robot_id))
        start_delay = parse_non_negative('~start_delay', get_param('~start_delay', 0.0))
        self._start_after = time.monotonic() + start_delay

        self._lock = threading.Lock()
        self._selected = NONE
        self._selection_seen = False
        self._switches = 0
        self._task_ids = itertools.count(1)

        self.sample_pubs = dict(
            (s, rospy.Publisher(names.sample_topic(self.robot_id, s), LatencySample, queue_size=10))
            for s in self.servers)
        self.report_pub = rospy.Publisher(names.TASK_REPORT_TOPIC, TaskReport, queue_size=100)
        self.flag_sub = rospy.Subscriber(names.SELECTION_TOPIC, SelectionFlag, self.on_flag,
                                         queue_size=100, tcp_nodelay=True)

        self.streams = []
        if get_param('~sort_tasks', True):
            self.streams.append(SortStream(
                self, parse_positive('~task_rate', get_param('~task_rate', 2.0)), task_limit,
                task_timeout, parse_positive('~task_size', get_param('~task_size', 1000),
                                             integer=True), seed))
        self.registry = TargetRegistry(
            parse_positive('~merge_radius', get_param('~merge_radius', 150.0)))
        self.found_pub = rospy.Publisher(names.FOUND_TARGETS_TOPIC, FoundTarget, queue_size=100,
                                         latch=False)
        self.found_sub = rospy.Subscriber(names.FOUND_TARGETS_TOPIC, FoundTarget,
                                          self.on_found, queue_size=100, tcp_nodelay=True)
        self.known_srv = rospy.Service(names.KNOWN_TARGETS_SERVICE, KnownTargets,
                                       self.on_known_targets)
        image_source = get_param('~image_source', '')
        if image_source:
            self.streams.append(self._image_stream(image_source, task_limit, task_timeout))
        if not self.streams:
            raise ParamError('~sort_tasks is false and ~image_source is empty: no tasks to send')

        self.proxies = dict(
            (s, TimedServiceProxy(names.probe_service(s), LatencyProbe)) for s in self.servers)
        self._probe_seq = itertools.count(1)
        self._probe_pool = concurrent.futures.ThreadPoolExecutor(
            max_workers=len(self.servers), thread_name_prefix='probe')
        self._inflight = {}
        self._probe_ok = set()

        self.probe_timer = rospy.Timer(rospy.Duration(1.0 / self.probe_rate), self.on_probe_timer)
        self.summary_timer = rospy.Timer(rospy.Duration(summary_period), self.on_summary_timer)
        rospy.on_shutdown(self.on_shutdown)
        rospy.loginfo('robot %d: mode %s%s, probing servers %s at %.3g Hz, tasks: %s',
                      self.robot_id, self.mode,
                      ' (server %d)' % self.fixed_server if self.mode == 'fixed' else '',
                      self.servers, self.probe_rate, ', '.join(s.kind for s in self.streams))

    def _image_stream(self, spec, limit, timeout):
        encoding = get_param('~image_encoding', 'bgr8')
        if encoding not in ('bgr8', 'rgb8', 'mono8'):
            raise ParamError('~image_encoding: %r is not one of bgr8, rgb8, mono8' % encoding)
        index = parse_non_negative('~robot_index', get_param('~robot_index', 0))
        count = parse_positive('~robot_count', get_param('~robot_count', 1), integer=True)
        try:
            source = open_source(spec, int(index), count,
                                 parse_positive('~speed', get_param('~speed', 200.0)))
        except (SourceError, SearchError, OSError) as error:
            raise ParamError('~image_source: %s' % error)
        local_detector = None
        if self.mode == 'local':
            try:
                local_detector = Detector(
                    kind=get_param('~detector', 'haar'),
                    cascade=get_param('~cascade', 'haarcascade_frontalface_default.xml'))
            except DetectorError as error:
                raise ParamError('~detector/~cascade: %s' % error)
        return ImageStream(self, parse_positive('~frame_rate', get_param('~frame_rate', 10.0)),
                           limit, timeout, source, encoding, self.registry, self.found_pub,
                           local_detector)

    def next_task_id(self):
        return next(self._task_ids)

    # -- probing ---------------------------------------------------------------------------

    def on_probe_timer(self, _event):
        if rospy.is_shutdown():
            return
        for server in self.servers:
            previous = self._inflight.get(server)
            if previous is not None and not previous.done():
                self._publish_sample(server, next(self._probe_seq), rospy.Time.now(), None,
                                     'previous probe still in progress')
                continue
            try:
                self._inflight[server] = self._probe_pool.submit(
                    self._probe, server, next(self._probe_seq))
            except RuntimeError:  # pool shut down: the node is stopping
                return

    def _probe(self, server, seq):
        stamp = rospy.Time.now()
        request = LatencyProbeRequest(robot_id=self.robot_id, seq=seq, stamp=stamp)
        try:
            response, rtt = self.proxies[server].call_within(request, self.probe_timeout)
        except rospy.ServiceException as error:
            self._publish_sample(server, seq, stamp, None, str(error))
            return
        if response.server_id != server or response.seq != seq:
            self._publish_sample(server, seq, stamp, None, 'answer from server %d seq %d'
                                 % (response.server_id, response.seq))
            return
        self._publish_sample(server, seq, stamp, rtt, '')
        self._probe_ok.add(server)

    def _publish_sample(self, server, seq, stamp, rtt, error):
        sample = LatencySample(robot_id=self.robot_id, server_id=server, seq=seq,
                               ok=rtt is not None, rtt=rtt or 0.0, error=error)
        sample.header.stamp = stamp
        if error:
            rospy.logdebug('robot %d: probe of server %d failed: %s', self.robot_id, server, error)
        self.sample_pubs[server].publish(sample)

    # -- selection -------------------------------------------------------------------------

    def on_flag(self, flag):
        if flag.robot_id != self.robot_id:
            return
        with self._lock:
            self._selection_seen = True
            if flag.server_id != self._selected:
                if self._selected != NONE:
                    self._switches += 1
                rospy.loginfo('robot %d: selected server %s (ranking %s)', self.robot_id,
                              flag.server_id if flag.server_id != NONE else 'none',
                              list(flag.ranking))
                self._selected = flag.server_id

    def target(self):
        """The server a task sent now goes to (NONE when there is none)."""
        if self.mode == 'fixed':
            return self.fixed_server
        with self._lock:
            return self._selected

    def ready(self, stream):
        """A stream starts once its target answers and its topics are wired."""
        if time.monotonic() < self._start_after:
            return False
        if self.mode == 'local':
            return True
        if self.mode == 'fixed':
            target_up = self.fixed_server in self._probe_ok
        else:
            with self._lock:
                target_up = self._selection_seen and self._selected != NONE
        return target_up and stream.wired()

    # -- cooperative search ----------------------------------------------------------------

    def on_found(self, msg):
        if msg.robot_id != self.robot_id:
            self.registry.add(Found(msg.robot_id, msg.task_id, msg.label, msg.x, msg.y,
                                    msg.header.stamp.to_sec()))

    def on_known_targets(self, _request):
        return KnownTargetsResponse(targets=[
            FoundTarget(header=self._header(f.stamp), robot_id=f.robot_id, task_id=f.task_id,
                        label=f.label, x=f.x, y=f.y) for f in self.registry.all()])

    @staticmethod
    def _header(stamp):
        return Header(stamp=rospy.Time.from_sec(stamp))

    # -- reporting -------------------------------------------------------------------------

    def summary(self):
        with self._lock:
            switches = self._switches
        target = self.target() if self.mode != 'local' else 'local'
        return 'robot %d: %s; server %s, %d switches' % (
            self.robot_id, '; '.join(s.summary() for s in self.streams),
            target if target != NONE else 'none', switches)

    def on_summary_timer(self, _event):
        rospy.loginfo(self.summary())

    def on_shutdown(self):
        for timer in (self.probe_timer, self.summary_timer):
            timer.shutdown()
        for stream in self.streams:
            stream.shutdown()
        self._probe_pool.shutdown(wait=False)
        for proxy in self.proxies.values():
            proxy.close()
        rospy.loginfo(self.summary())


def main():
    run('robot', RobotNode)
