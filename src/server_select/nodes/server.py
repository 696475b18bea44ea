"""Compute server: answers latency probes, and the tasks of every type addressed to it."""

import collections
import concurrent.futures
import threading
import time

import rospy

from server_select.core.config import names
from server_select.core.config.params import ParamError
from server_select.core.util.procs import usable_cpus
from server_select.ros import bounded_read, seal
from server_select.ros.membership import ServerAnnouncer
from server_select.ros.node import fleet, live_param, param
from server_select.ros.runner import run
from server_select.ros.plugins import PluginHandler
from server_select.ros.robot_admission import RobotAdmission
from server_select.ros.server_work import ServerWork
from server_select.tasks.kinds import server_kinds
from server_select.srv import LatencyProbe, LatencyProbeResponse

KNOWN_ROBOTS = 4096     # robots whose probes prepared their result topics, remembered
MAX_PROBE_BYTES = 1 << 16   # a probe request: ids and the kinds a robot sends (~100 B each)


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
    in seconds, the utilization (the share of the workers' time the other robots' tasks
    take, at the rates their probes announce or, for robots that announce none, at which
    they arrive) and the recent work per task of each kind. With a fleet key a robot's
    tasks and announced rates count only from the node whose signed probe named it
    (:mod:`~server_select.ros.robot_admission`); too long a task or probe is refused from
    its length, unread (:mod:`~server_select.ros.bounded_read`).

    :ROS Parameters:
        - ``~server_id`` (int, required): this server's id.
        - ``~profile`` (``paper``), ``~routing`` (``broadcast``; fleet: ``direct``)
        - ``~max_task_len`` (int, 100000): longer sort tasks are refused, unread.
        - ``~queue_size`` (int, 100): task subscriber queues.
        - ``~workers`` (int, 0: the cores this process may use, its cgroup's CPU quota
          rounded up): tasks worked on at once.
        - ``~max_queue`` (int, 100): tasks waiting for a worker; more are answered busy.
        - ``~max_queue_bytes`` (int, 32 MiB): memory those tasks may hold; more: busy.
        - ``~summary_period`` (s, 10): period of the log line of what it has done.
        - ``~work_delay`` (s, 0): each task takes this much longer (a slower machine).
        - ``~check_every`` (s, 0; fleet: 0.5): while no robot sends here, a copy of the
          last task of a kind not timed for this long (nor for 20 of its tasks' work) is
          worked on again, so that probe answers say what one takes now.
        - ``~test_knobs`` (bool, false): follow ``~work_delay`` at run time (``rosparam
          set``, for tests and the testbed); off, it is read once at start.
        - ``~detector`` (str, ``haar``): ``haar`` or ``hog``.
        - ``~cascade`` (str, ``haarcascade_frontalface_default.xml``)
        - ``~scale_factor`` (1.2), ``~min_neighbors`` (5), ``~min_size`` (24 px): cascade settings.
        - ``~max_image_pixels`` (int, 2097152): larger frames are refused (raw: unread).
        - ``~jpeg_quality`` (80): of the annotated frame sent back for a compressed task.
        - ``~announce_period`` (s, 2): period of its announcement on
          ``server_announcements`` (latched; a lease of 3 periods; "leaving" at shutdown).
        - ``~task_plugins`` ([]): more task types, ``module:Class`` of
          :class:`~server_select.ros.plugins.TaskPlugin` (e.g. ``server_select.tasks.orb:Orb``).
    :ROS Services:
        - ``latency_S<server_id>`` (server_select/LatencyProbe): echo for RTT probing.
    :ROS Subscribers:
        - ``data`` (server_select/SortTask), ``task_image`` (server_select/ImageTask)
    :ROS Publishers:
        - ``server_announcements`` (server_select/ServerAnnouncement, latched)
        - ``processed_data`` (server_select/SortResult): one result per sort task addressed here.
        - ``processed_image`` (server_select/ImageResult): one result per frame addressed here,
          with the annotated frame.
        - ``detections`` (server_select/Detections): what was found in each frame, under
          the frame's header (its stamp and frame_id).
    """
    SEAL_ROLE = 'server'  # what it signs as with a fleet key (core/trust/seal.py)
    DIAGNOSTICS = 'server'  # its statuses on /diagnostics (ros/diagnostics.py)

    def __init__(self):
        self.server_id = param('server_id')
        self.queue_size = param('queue_size')
        self.work_delay = param('work_delay')
        self.check_every = param('check_every')
        workers = param('workers') or usable_cpus()
        self.work = ServerWork(self.server_id, workers, param('max_queue'),
                               param('max_queue_bytes'))
        self.direct = direct = param('routing') == 'direct'
        self._known_robots = collections.OrderedDict()   # robots prepared for, newest last
        self._pool = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix='routes')
        self.stopped = False
        # every task type, built in or plug-in, is served the same way
        self.announcer = ServerAnnouncer(self.server_id, param('announce_period'))
        self.admission = RobotAdmission('server %d' % self.server_id, rospy.resolve_name(
            fleet(names.probe_service(self.server_id))))
        self.handlers = [PluginHandler(self.server_id, kind, self._submit,
                                       self.queue_size, direct, work=self._work)
                         for kind in server_kinds(param, workers)]

    def handler(self, kind):
        """The handler of task type ``kind`` (``sort``, ``image``, a plug-in's)."""
        return next(h for h in self.handlers if h.plugin.kind == kind)

    def start(self):
        self._kinds = frozenset(h.plugin.kind for h in self.handlers)
        self._unwarmed = set(self._kinds)   # no probe named them yet
        self.test_knobs = param('test_knobs')
        if self.test_knobs:      # from now on as the master says: any node may change it
            self.work_delay = live_param('work_delay')
            rospy.logwarn('server %d: ~test_knobs is on: ~work_delay (now %g s) follows '
                          'rosparam set from any node', self.server_id, self.work_delay)
        for handler in self.handlers:
            handler.start()
        self.work.start()
        # Advertised last: a robot that can probe us finds our task topics wired already.
        self.probe_srv = rospy.Service(
            fleet(names.probe_service(self.server_id)), LatencyProbe, self.on_probe)
        bounded_read.limit(self.probe_srv.resolved_name, MAX_PROBE_BYTES)
        self.announcer.probe_uri = self.probe_srv.uri
        self.announcer.start()
        rospy.loginfo('server %d: probe service %s, tasks on %s',
                      self.server_id, self.probe_srv.resolved_name,
                      ', '.join(t for h in self.handlers for t in h.endpoint.topics))
        self.work_timer = rospy.Timer(rospy.Duration(1.0), self.on_work_check) \
            if self.test_knobs else None
        self.summary_timer = rospy.Timer(rospy.Duration(param('summary_period')),
                                         lambda _e: rospy.loginfo(self.summary()))
        rospy.on_shutdown(self.on_shutdown)

    def on_work_check(self, _event):
        """``~work_delay`` again (``rosparam set`` changes it while the server runs; the
        master tells the node, so reading it costs no call)."""
        try:
            delay = live_param('work_delay')
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

    def _submit(self, endpoint, task, direct):
        if self.admission.admits(task):
            self.work.submit(endpoint, task, direct)

    def on_probe(self, req):
        if self.admission.probe(req):
            self._heard(req)
            self.work.check(self.check_every)
        load = self.work.load(req.robot_id)
        return seal.seal_answer(LatencyProbeResponse(
            server_id=self.server_id, seq=req.seq, stamp=req.stamp, server_stamp=rospy.Time.now(),
            queued=load.queued, in_service=load.in_service, workers=load.workers,
            backlog=load.backlog, utilization=load.utilization, kinds=list(load.service),
            service_time=list(load.service.values()),
            service_error=[load.service_error.get(k, 0.0) for k in load.service]),
            self.probe_srv.resolved_name,
            self.probe_srv.uri, req)

    def _heard(self, req):
        """A robot's own probe: its result topics, and the rates it announces."""
        if self.direct and req.robot_id and req.robot_id not in self._known_robots:
            self._known_robots[req.robot_id] = True   # its result publishers, off this path
            while len(self._known_robots) > KNOWN_ROBOTS:
                self._known_robots.popitem(last=False)
            self._pool.submit(self._prepare, req.robot_id)
        elif self.direct:       # its result connections: stalled, or ended (an outage)
            node = (getattr(req, '_connection_header', None) or {}).get('callerid')
            cut = [(h, node if h.plugin.kind in req.task_kinds else None)
                   for h in self.handlers]
            if any(h.endpoint.cut_off(req.robot_id, asked) for h, asked in cut):
                self._pool.submit(self._renew, req.robot_id, cut)
        if req.task_kinds:      # (kinds it does not serve: nothing to keep)
            rates = zip(req.task_kinds, req.task_rates)
            self.work.announce(req.robot_id, [(k, r) for k, r in rates if k in self._kinds])
            for kind in self._unwarmed.intersection(req.task_kinds):   # before its 1st task
                self._unwarmed.discard(kind)
                threading.Thread(target=self._warm, args=(kind,), name='warm ' + kind,
                                 daemon=True).start()

    def _warm(self, kind):
        for handler in self.handlers:
            if handler.plugin.kind == kind:
                try:
                    handler.plugin.warm()
                except Exception as error:    # its first task will say it again
                    rospy.logwarn('server %d: cannot load what %s tasks need: %s: %s',
                                  self.server_id, kind, type(error).__name__, error)

    def _prepare(self, robot):
        for handler in self.handlers:
            handler.endpoint.prepare(robot)

    def _renew(self, robot, cut):
        for handler, node in cut:
            nodes = handler.endpoint.renew(robot, node)
            if nodes:
                rospy.logwarn('server %d: %s results to robot %d do not reach %s (stalled in '
                              'TCP back-off, or the connection ended): connecting anew',
                              self.server_id, handler.plugin.kind, robot, ', '.join(nodes))

    def on_shutdown(self):
        if self.stopped:       # (once: a node built in a test process is also stopped by it)
            return
        self.stopped = True
        self.announcer.leave()
        if self.work_timer is not None:
            self.work_timer.shutdown()
        self.summary_timer.shutdown()
        self._pool.shutdown(wait=False)
        self.work.shutdown()
        rospy.loginfo(self.summary())

    def summary(self):
        done = '; '.join('%s: %d done, %d rejected' % (h.plugin.kind, h.done, h.rejected)
                         for h in self.handlers)
        return 'server %d: %s; %s' % (self.server_id, done, self.work.summary())


def main():
    run('server', ServerNode)
