"""Compute server: answers latency probes, and the sort and image tasks addressed to it."""

import concurrent.futures
import queue
import threading
import time

import numpy as np
import rospy
from sensor_msgs.msg import CompressedImage, Image, RegionOfInterest

from server_select.core import names
from server_select.core.params import ParamError
from server_select.core.procs import usable_cpus
from server_select.core.sort_task import TaskError, sort_values
from server_select.msg import Detection, Detections, ImageResult, SortResult
from server_select.ros.node import fleet, param, run
from server_select.ros.plugins import PluginHandler, load as load_plugin
from server_select.ros.routing import ServerEndpoint
from server_select.ros.server_work import ServerWork
from server_select.ros.task_kinds import ImageKind, SortKind
from server_select.srv import LatencyProbe, LatencyProbeResponse
from server_select.vision import image_codec
from server_select.vision.detection import DetectorError, make_detector, search_frame

EMPTY = np.empty(0, dtype=np.int32)


class ServerNode(object):
    """A compute server of the fleet.

    Tasks are broadcast on ``data`` to every server; each task names the server the robot
    selected when it sent it, and only that server processes it. Deciding by the id
    stamped in the task (rather than by the latest flag each server happens to have seen)
    is what keeps one task from being answered twice, or not at all, around a switch.
    With ``~routing`` ``direct`` (fleet profile) the server also takes tasks on its own
    topics (``server_<id>/data``, ...) and answers those on the sending robot's own topic
    (``robot_<r>/processed_data``, ...).

    Image tasks are searched for targets with an OpenCV Haar cascade (``~cascade``, a file
    of OpenCV's cascade folder or a path) or the HOG people detector (``~detector:=hog``);
    raw frames in ``bgr8``, ``rgb8`` or ``mono8`` (any row padding) and compressed ones
    (JPEG, PNG) are accepted, anything else gets an error result; a compressed task gets
    its annotated frame back as JPEG.

    Every task addressed here, of every kind, waits in one bounded queue for one of
    ``~workers`` workers. A task whose robot gave it a deadline (``budget``) that the
    queue's backlog says cannot be met is answered *busy* at once; one whose deadline
    passes while it waits is answered busy when a worker takes it (stale work is shed, not
    done). Every probe answer carries the load: tasks queued and in service, the backlog
    in seconds, and the recent work per task of each kind.

    :ROS Parameters:
        - ``~server_id`` (int, required): this server's id.
        - ``~profile`` (``paper``), ``~routing`` (``broadcast``; fleet: ``direct``)
        - ``~max_task_len`` (int, 1000000): larger sort tasks get an error result.
        - ``~queue_size`` (int, 100): task subscriber queues.
        - ``~workers`` (int, 0: the cores this process may use, its cgroup's CPU quota
          rounded up): tasks worked on at once.
        - ``~max_queue`` (int, 100): tasks waiting for a worker; more are answered busy.
        - ``~summary_period`` (s, 10): period of the log line of what it has done.
        - ``~detector`` (str, ``haar``): ``haar`` or ``hog``.
        - ``~cascade`` (str, ``haarcascade_frontalface_default.xml``)
        - ``~scale_factor`` (1.2), ``~min_neighbors`` (5), ``~min_size`` (24 px): cascade settings.
        - ``~max_image_pixels`` (int, 16777216): larger frames get an error result.
        - ``~jpeg_quality`` (80): of the annotated frame sent back for a compressed task.
        - ``~task_plugins`` ([]): more task types, ``module:Class`` of
          :class:`~server_select.ros.plugins.TaskPlugin` (e.g. ``server_select.tasks.orb:Orb``).
    :ROS Services:
        - ``latency_S<server_id>`` (server_select/LatencyProbe): echo for RTT probing.
    :ROS Subscribers:
        - ``data`` (server_select/SortTask), ``task_image`` (server_select/ImageTask)
    :ROS Publishers:
        - ``processed_data`` (server_select/SortResult): one result per sort task addressed here.
        - ``processed_image`` (server_select/ImageResult): one result per frame addressed here,
          with the annotated frame.
        - ``detections`` (server_select/Detections): what was found in each frame.
    """

    def __init__(self):
        self.server_id = param('server_id')
        self.max_task_len = param('max_task_len')
        self.queue_size = param('queue_size')
        self.max_image_pixels = param('max_image_pixels')
        self.jpeg_quality = param('jpeg_quality')
        self.work_delay = param('work_delay')
        workers = param('workers') or usable_cpus()
        self.work = ServerWork(self.server_id, workers, param('max_queue'))
        # one detector a worker: a detector searches one frame at a time
        self.detectors = queue.Queue()
        try:
            for _ in range(workers):
                self.detectors.put(make_detector(param))
        except DetectorError as error:
            raise ParamError('~detector/~cascade: %s' % error)
        self.direct = direct = param('routing') == 'direct'
        self._known_robots = set()
        self._pool = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix='routes')
        submit = self.work.submit
        self.plugins = [PluginHandler(self.server_id, load_plugin(spec, None), submit,
                                      self.queue_size, direct)
                        for spec in param('task_plugins')]
        self.endpoints = [ServerEndpoint(self.server_id, kind, handle, direct, submit,
                                         self.queue_size)
                          for kind, handle in ((SortKind, self.on_sort_task),
                                               (ImageKind, self.on_image_task))]
        self._lock = threading.Lock()
        self.tasks_done = 0
        self.tasks_failed = 0

    def start(self):
        self.detections_pub = rospy.Publisher(fleet(names.DETECTIONS_TOPIC), Detections,
                                              queue_size=self.queue_size)
        for endpoint in self.endpoints:
            endpoint.start()
        for plugin in self.plugins:
            plugin.start()
        self.work.start()
        # Advertised last: a robot that can probe us finds our task topics wired already.
        self.probe_srv = rospy.Service(
            fleet(names.probe_service(self.server_id)), LatencyProbe, self.on_probe)
        rospy.loginfo('server %d: probe service %s, tasks on %s',
                      self.server_id, self.probe_srv.resolved_name,
                      ', '.join(t for e in self.endpoints for t in e.topics))
        self.work_timer = rospy.Timer(rospy.Duration(1.0), self.on_work_check)
        self.summary_timer = rospy.Timer(rospy.Duration(param('summary_period')),
                                         lambda _e: rospy.loginfo(self.summary()))
        rospy.on_shutdown(self.on_shutdown)

    def on_work_check(self, _event):
        """``~work_delay`` again (``rosparam set`` changes it while the server runs)."""
        try:
            delay = param('work_delay')
        except ParamError as error:
            rospy.logwarn_throttle(30.0, 'server %d: %s (keeping %g s)'
                                   % (self.server_id, error, self.work_delay))
            return
        if delay != self.work_delay:
            rospy.loginfo('server %d: each task now takes %g s more', self.server_id, delay)
            self.work_delay = delay

    def _work(self):
        if self.work_delay:
            time.sleep(self.work_delay)

    def on_probe(self, req):
        if self.direct and req.robot_id not in self._known_robots:
            self._known_robots.add(req.robot_id)   # its result publishers, off this path
            self._pool.submit(self._prepare, req.robot_id)
        load = self.work.load()
        return LatencyProbeResponse(
            server_id=self.server_id, seq=req.seq, stamp=req.stamp, server_stamp=rospy.Time.now(),
            queued=load.queued, in_service=load.in_service, workers=load.workers,
            backlog=load.backlog, kinds=list(load.service),
            service_time=list(load.service.values()))

    def _prepare(self, robot):
        for endpoint in self.endpoints + [p.endpoint for p in self.plugins]:
            endpoint.prepare(robot)

    def on_sort_task(self, task):
        """The result of a sort task."""
        result = SortResult(header=task.header, robot_id=task.robot_id, task_id=task.task_id,
                            server_id=self.server_id, data=EMPTY)
        start = time.perf_counter()
        try:
            result.data = sort_values(task.data, self.max_task_len)
            result.ok = True
            self._work()
        except TaskError as error:
            self._reject(result, 'task', task, error)
        result.process_time = time.perf_counter() - start
        self._count(result.ok)
        return result

    def on_image_task(self, task):
        """The result of a frame."""
        result = ImageResult(header=task.header, robot_id=task.robot_id, task_id=task.task_id,
                             server_id=self.server_id)
        start = time.perf_counter()
        img, packed = task.image, task.compressed
        try:
            boxes, annotated = self._search(img, packed)
        except image_codec.ImageError as error:
            self._reject(result, 'frame', task, error)
        else:
            self._annotated(result, annotated, img.header if not packed.data else None,
                            packed.header)
            result.ok = True
            self._work()
            result.detection_count = len(boxes)
            self.detections_pub.publish(Detections(
                header=task.header, robot_id=task.robot_id, task_id=task.task_id,
                server_id=self.server_id, detections=[
                    Detection(roi=RegionOfInterest(x_offset=b.x, y_offset=b.y, width=b.width,
                                                   height=b.height),
                              label=b.label, score=b.score) for b in boxes]))
        result.process_time = time.perf_counter() - start
        self._count(result.ok)
        return result

    def _search(self, img, packed):
        """Boxes and annotated frame of a task's raw (``img``) or ``packed`` frame, with a
        detector of this worker's own."""
        detector = self.detectors.get()
        try:
            return search_frame(detector, (img.encoding, img.height, img.width, img.step,
                                           img.data), (packed.format, packed.data),
                                self.max_image_pixels)
        finally:
            self.detectors.put(detector)

    def _annotated(self, result, frame, raw_header, compressed_header):
        """The annotated frame into ``result``: raw for a raw task (``raw_header``), JPEG
        for a compressed one."""
        if raw_header is not None:
            encoding, height, width, step, data = image_codec.from_array(frame)
            result.image = Image(header=raw_header, height=height, width=width,
                                 encoding=encoding, step=step, data=data)
        else:
            fmt, data = image_codec.encode(frame, self.jpeg_quality)
            result.compressed = CompressedImage(header=compressed_header, format=fmt, data=data)

    def _reject(self, result, what, task, error):
        result.ok = False
        result.error = str(error)
        rospy.logerr('server %d: %s %d of robot %d rejected: %s',
                     self.server_id, what, task.task_id, task.robot_id, error)

    def _count(self, ok):
        with self._lock:
            if ok:
                self.tasks_done += 1
            else:
                self.tasks_failed += 1

    def on_shutdown(self):
        self.work_timer.shutdown()
        self.summary_timer.shutdown()
        self._pool.shutdown(wait=False)
        self.work.shutdown()
        rospy.loginfo(self.summary())

    def summary(self):
        return 'server %d: %d tasks done, %d rejected; %s%s' % (
            self.server_id, self.tasks_done, self.tasks_failed, self.work.summary(),
            ''.join('; %s: %d done, %d rejected' % (p.plugin.kind, p.done, p.rejected)
                    for p in self.plugins))


def main():
    run('server', ServerNode)
