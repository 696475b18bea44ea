"""``rosrun server_select top``: a live view of the fleet in the terminal, or of a bag.

    rosrun server_select top [--servers 1,2,3] [--once] [--seconds S]
    rosrun server_select top --bag run.bag [--speed 10] [--once]

Live, it listens to the fleet's own topics (``task_report``, ``server_select_flag``,
``latency_samples``, ``server_announcements``, ``/rosout_agg``) and probes each server it
knows once a second (as robot 0, an observer: the servers keep no state for it) for its
load; a server that stops answering shows as gone within about 1.5 s. The screen is
redrawn twice a second (curses; ``q`` quits, so does Ctrl-C). ``--once`` (or output that is
not a terminal) prints one view after ``--seconds`` and exits. ``--bag`` replays a recorded
run through the same view (no probes: a server is up while it answers tasks).
"""

import argparse
import concurrent.futures
import curses
import sys
import threading
import time

from server_select.core.observe.fleet_view import FleetView, Load
from server_select.ros import bags

TOPICS = ('task_report', 'server_select_flag', 'latency_samples', 'server_announcements',
          'rosout_agg', 'rosout')
PERIOD = 0.5           # s between frames
PROBE_PERIOD = 1.0     # s between the probes of a server
PROBE_TIMEOUT = 0.5


def samples_of(msg):
    """``(server, ok, rtt)`` of a fleet robot's probe round or of one paper sample."""
    if isinstance(msg.server_id, int):
        return [(msg.server_id, msg.ok, msg.rtt)]
    return list(zip(msg.server_id, msg.ok, msg.rtt))


class Feed(object):
    """Hands the fleet's messages to a :class:`FleetView` (thread-safe)."""

    def __init__(self, view, clock):
        self.view, self.clock = view, clock
        self.lock = threading.Lock()

    def message(self, topic, msg, now=None):
        now = self.clock() if now is None else now
        kind = bags.kind_of(topic)
        with self.lock:
            if kind == 'task_report':
                self.view.task(msg.robot_id, msg.server_id, msg.answered_by, msg.ok, now)
            elif kind == 'server_select_flag':
                self.view.flag(msg.robot_id, msg.server_id, msg.ranking, now,
                               getattr(msg, 'reason', ''))   # (older bags: none)
            elif kind in ('latency_samples', bags.PAIR):      # fleet, paper
                for server, ok, rtt in samples_of(msg):
                    self.view.sample(msg.robot_id, server, ok, rtt, now)
            elif kind == 'server_announcements':
                self.view.announcement(msg.server_id, msg.lease, now)
            elif kind in ('rosout_agg', 'rosout'):
                self.view.log(msg.msg, now)

    def update(self, now):
        """The view brought to ``now`` (its alerts at their time), not rendered."""
        with self.lock:
            self.view.update(now)

    def lines(self, now=None):
        with self.lock:
            now = self.clock() if now is None else now
            return self.view.lines(now, lambda t: time.strftime(
                '%H:%M:%S', time.localtime(t)) if t > 1e9 else '%.1f s' % t)


class LiveFleet(object):
    """The ROS side of the live view: subscribers and the viewer's own probes."""

    def __init__(self, feed, servers):
        import rospy
        from rosgraph_msgs.msg import Log
        from server_select.core.config import names
        from server_select.msg import (LatencySamples, SelectionFlag, ServerAnnouncement,
                                       TaskReport)
        from server_select.ros.node import fleet
        self.rospy, self.feed = rospy, feed
        self.servers, self.proxies = set(servers), {}
        self.pool = concurrent.futures.ThreadPoolExecutor(8, thread_name_prefix='top')
        self.subs = [rospy.Subscriber(fleet(name), cls, self.on, fleet(name), queue_size=1000)
                     for name, cls in ((names.TASK_REPORT_TOPIC, TaskReport),
                                       (names.SELECTION_TOPIC, SelectionFlag),
                                       (names.SAMPLES_TOPIC, LatencySamples),
                                       (names.ANNOUNCE_TOPIC, ServerAnnouncement))]
        self.subs.append(rospy.Subscriber('/rosout_agg', Log, self.on_log, queue_size=1000))
        self._probe_name = lambda s: fleet(names.probe_service(s))
        self._running = {}

    def on(self, msg, topic):
        if topic.endswith('server_announcements'):
            self.servers.add(msg.server_id)
        self.feed.message(topic, msg)

    def on_log(self, msg):
        if msg.level >= msg.WARN or 'tasks go to server' in msg.msg:
            self.feed.message('rosout_agg', msg)

    def probe_all(self):
        for server in sorted(self.servers):
            running = self._running.get(server)
            if running is None or running.done():
                self._running[server] = self.pool.submit(self.probe, server)

    def probe(self, server):
        from server_select.ros.probe_client import TimedServiceProxy
        from server_select.srv import LatencyProbe, LatencyProbeRequest
        proxy = self.proxies.get(server)
        if proxy is None:
            proxy = self.proxies[server] = TimedServiceProxy(self._probe_name(server),
                                                             LatencyProbe)
        try:
            answer, _ = proxy.call_within(LatencyProbeRequest(robot_id=0), PROBE_TIMEOUT)
        except self.rospy.ServiceException as error:
            with self.feed.lock:
                self.feed.view.probe(server, False, None, self.feed.clock(), str(error))
            return
        with self.feed.lock:
            self.feed.view.probe(server, True, Load(answer.queued, answer.in_service,
                                                    answer.workers, answer.utilization),
                                 self.feed.clock())

    def close(self):
        for sub in self.subs:
            sub.unregister()
        self.pool.shutdown(wait=False)


def show(frames, once, out=sys.stdout):
    """Draw each frame ``frames`` yields (lists of lines): in curses on a terminal, else
    (or ``once``) print the last one."""
    if once or not out.isatty():
        last = None
        for last in frames:
            pass
        print('\n'.join(last or []), file=out)
        return

    def run(screen):
        curses.curs_set(0)
        screen.nodelay(True)
        for lines in frames:
            screen.erase()
            height, width = screen.getmaxyx()
            for row, line in enumerate(lines[:height - 1]):
                screen.addnstr(row, 0, line, width - 1)
            screen.refresh()
            if screen.getch() in (ord('q'), ord('Q')):
                return
    curses.wrapper(run)


def live_frames(args):
    import rospy
    rospy.init_node('top', anonymous=True, disable_signals=True)
    feed = Feed(FleetView(), time.time)
    live = LiveFleet(feed, args.servers)
    end = time.monotonic() + args.seconds if args.once else None
    probed = 0.0
    try:
        while not rospy.is_shutdown() and (end is None or time.monotonic() < end):
            if time.monotonic() - probed >= PROBE_PERIOD:
                probed = time.monotonic()
                live.probe_all()
            yield feed.lines()
            time.sleep(PERIOD)
        yield feed.lines()
    finally:
        live.close()
        rospy.signal_shutdown('top done')


def bag_frames(args):
    import rosbag
    try:
        rosbag.Bag(args.bag).close()
    except (OSError, rosbag.ROSBagException) as error:
        raise OSError('%s: %s' % (args.bag, error))
    feed = Feed(FleetView(), None)
    next_frame, now, last_task = None, None, None
    for kind, msg, now, _sender in bags.read(args.bag, TOPICS + (bags.PAIR,)):
        if next_frame is None:
            next_frame = now + PERIOD
        while now >= next_frame:    # --once: the last view only, its alerts in time
            if args.once:
                feed.update(next_frame)
            else:
                yield feed.lines(next_frame)
                time.sleep(PERIOD / args.speed)
            next_frame += PERIOD
        if kind == 'server_announcements':
            feed.view.probe(msg.server_id, True, None, now)   # announced: up
        if kind in ('latency_samples', bags.PAIR):   # a robot's probe reached it
            for server in [s for s, ok, _ in samples_of(msg) if ok]:
                feed.view.probe(server, True, None, now)
        if kind == 'task_report':
            last_task = now
            if msg.ok and msg.answered_by > 0:
                feed.view.probe(msg.answered_by, True, None, now)
        feed.message(kind, msg, now)
    if now is not None:     # the run as its last task saw it (then the robots stopped)
        yield feed.lines(last_task if last_task is not None else now)


def parse(argv):
    parser = argparse.ArgumentParser(prog='top', description=__doc__.split('\n\n')[0])
    parser.add_argument('--bag', help='replay this bag instead of the live fleet')
    parser.add_argument('--speed', type=float, default=10.0,
                        help='--bag: replay this many times faster than recorded')
    parser.add_argument('--servers', default='', help='server ids to probe from the start '
                        '(others as they announce themselves)')
    parser.add_argument('--once', action='store_true', help='print one view and exit')
    parser.add_argument('--seconds', type=float, default=3.0,
                        help='--once, live: listen this long first')
    args = parser.parse_args(argv)
    try:
        args.servers = [int(s) for s in args.servers.split(',') if s]
    except ValueError:
        parser.error('--servers: expected ids like 1,2,3, got %r' % args.servers)
    if args.speed <= 0 or args.seconds < 0:
        parser.error('--speed must be > 0 and --seconds >= 0')
    return args


def main(argv=None):
    import rospy
    args = parse(rospy.myargv(sys.argv)[1:] if argv is None else argv)
    try:
        show(bag_frames(args) if args.bag else live_frames(args), args.once)
    except KeyboardInterrupt:
        pass
    except OSError as error:
        print('top: %s' % error, file=sys.stderr)
        return 1
    return 0
