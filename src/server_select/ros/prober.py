"""A robot's probing of its servers: one timed LatencyProbe call per server per period."""

import concurrent.futures
import itertools

import rospy

from server_select.core import names
from server_select.msg import LatencySample
from server_select.ros.node import fleet
from server_select.ros.probe_client import TimedServiceProxy
from server_select.srv import LatencyProbe, LatencyProbeRequest


class Prober(object):
    """Probes every server every ``1/rate`` s and publishes each sample, failed ones too.

    Each server is probed from its own worker thread over a persistent connection, every
    call bounded by ``timeout``; a server whose previous probe is still running gets a
    failed sample instead of a second call. ``answered`` is the set of servers that have
    answered at least once; ``on_sample(server, ok, rtt, error)`` hears every sample.
    """

    def __init__(self, robot_id, servers, rate, timeout, on_sample=None):
        self.robot_id = robot_id
        self.servers = list(servers)
        self.rate = rate
        self.timeout = timeout
        self.answered = set()
        self.on_sample = on_sample or (lambda server, ok, rtt, error: None)
        self._seq = itertools.count(1)
        self._inflight = {}
        self._pubs = dict((s, rospy.Publisher(fleet(names.sample_topic(robot_id, s)),
                                              LatencySample, queue_size=10))
                          for s in self.servers)
        self._proxies = dict((s, TimedServiceProxy(fleet(names.probe_service(s)), LatencyProbe))
                             for s in self.servers)
        self._pool = concurrent.futures.ThreadPoolExecutor(
            max_workers=len(self.servers), thread_name_prefix='probe')
        self._timer = None

    def start(self):
        self._timer = rospy.Timer(rospy.Duration(1.0 / self.rate), self.on_timer)

    def on_timer(self, _event):
        if rospy.is_shutdown():
            return
        for server in self.servers:
            previous = self._inflight.get(server)
            if previous is not None and not previous.done():
                self._publish(server, next(self._seq), rospy.Time.now(), None,
                              'previous probe still in progress')
                continue
            try:
                self._inflight[server] = self._pool.submit(self._probe, server, next(self._seq))
            except RuntimeError:  # pool shut down: the node is stopping
                return

    def _probe(self, server, seq):
        stamp = rospy.Time.now()
        request = LatencyProbeRequest(robot_id=self.robot_id, seq=seq, stamp=stamp)
        try:
            response, rtt = self._proxies[server].call_within(request, self.timeout)
        except rospy.ServiceException as error:
            self._publish(server, seq, stamp, None, str(error))
            return
        if response.server_id != server or response.seq != seq:
            self._publish(server, seq, stamp, None, 'answer from server %d seq %d'
                          % (response.server_id, response.seq))
            return
        self._publish(server, seq, stamp, rtt, '')
        self.answered.add(server)

    def _publish(self, server, seq, stamp, rtt, error):
        sample = LatencySample(robot_id=self.robot_id, server_id=server, seq=seq,
                               ok=rtt is not None, rtt=rtt or 0.0, error=error)
        sample.header.stamp = stamp
        if error:
            rospy.logdebug('robot %d: probe of server %d failed: %s', self.robot_id, server, error)
        self._pubs[server].publish(sample)
        self.on_sample(server, not error, rtt, error)

    def shutdown(self):
        if self._timer is not None:
            self._timer.shutdown()
        self._pool.shutdown(wait=False)
        for proxy in self._proxies.values():
            proxy.close()
