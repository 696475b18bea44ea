"""The robot node's probes on the wire: LatencyProbe calls when its robot's plan says, each
answer checked before the robot hears it, each sample published."""

import collections
import concurrent.futures
import random
import threading

import rospy

from server_select.core.config import names
from server_select.core.robot.probe_plan import ProbeRound
from server_select.ros.node import fleet
from server_select.ros.probe_client import TimedServiceProxy
from server_select.ros.probe_loop import ProbeLoop
from server_select.ros.probe_samples import ProbeSamples
from server_select.ros.probe_seal import ProbeSeal
from server_select.ros.seal import enabled as keyed
from server_select.srv import LatencyProbe, LatencyProbeRequest

ROUNDS_KEPT = 16     # rounds whose batch may still be waiting for a probe's end


class Prober(object):
    """Runs ``robot``'s probe rounds (a :class:`~server_select.core.robot.robot.Robot`, whose
    plan decides what is probed when) on one loop thread over persistent connections (a
    probe that must connect first, on a worker thread), each bounded by ``timeout``.

    An answer reaches the robot only once checked: from the server probed, for this probe,
    and, with a fleet key, sealed by the node ``node_of(server, refresh)`` names (with
    ``addresses``, a ``ProbeAddresses``: at the address, and by the node, its sealed
    announcement names); anything else is a failed probe naming who answered. ``load_of``
    (load-aware) reads an answer's load report (one it cannot read fails the probe).
    Samples go out as ``stream`` says (``ProbeSamples``; ``view``: for recorders, the
    manager hears the robot's own ranking), a batch per round; ``after_answers`` is called
    once after each batch of answers.
    """

    def __init__(self, robot_id, timeout, stream='pair', load_of=None, node_of=None,
                 addresses=None):
        self.robot_id, self.timeout = robot_id, timeout
        self.robot = None
        self.load_of = load_of
        self.seal = ProbeSeal(robot_id, node_of, addresses)
        self._nonce, self._keyed = random.SystemRandom(), keyed()
        self._lock = threading.Lock()
        self._proxies = {}
        self._stamps = {}            # server -> (seq, stamp) of its probe out
        self._rounds = collections.OrderedDict()     # number -> ProbeRound (batched)
        self.samples = ProbeSamples(robot_id, stream, load_of is not None)
        self._pool = concurrent.futures.ThreadPoolExecutor(max_workers=16,
                                                           thread_name_prefix='probe')
        self.after_answers = None    # called once after each batch of samples
        self._loop = ProbeLoop(self.on_round, self._next_time, self._on_error,
                               after=self._after)

    def add(self, server):
        with self._lock:
            if server in self._proxies:
                return
            self.samples.add(server)
            self._proxies[server] = TimedServiceProxy(
                fleet(names.probe_service(server)), LatencyProbe, *self.seal.proxy_args(server))
        self._loop.poke()

    def remove(self, server):
        with self._lock:
            proxy = self._proxies.pop(server, None)
            self._stamps.pop(server, None)
        if proxy is not None:
            proxy.close()
        self.samples.remove(server)

    def start(self, robot):
        self.robot = robot
        self._loop.start()

    def _next_time(self):
        return self.robot.next_probe_time()

    def _on_error(self, error):
        rospy.logerr_throttle(5.0, 'robot %d: probing: %s: %s' % (
            self.robot_id, type(error).__name__, error))

    def on_round(self):
        if rospy.is_shutdown():
            self._loop.stop()
            return
        self.robot.probe_round()

    def round(self, number, servers):
        """The robot's round ``number`` starts: its batch, stamped now."""
        with self._lock:
            stamp = rospy.Time.now()
            self._rounds[number] = ProbeRound(number, stamp, servers) \
                if self.samples.batched else stamp
            while len(self._rounds) > ROUNDS_KEPT:
                self._rounds.popitem(last=False)

    def probe(self, server, seq, kinds, rates):
        """Send probe ``seq`` to ``server`` (the robot's round, on the loop thread)."""
        proxy = self._proxies.get(server)
        if proxy is not None and proxy.connected():     # on the loop: one wake-up
            request = self._request(server, seq, kinds, rates)
            return self._loop.start_probe(proxy, request, self.timeout,
                                          self._then(server, seq, request, proxy))
        try:    # a connection first: on a worker thread, not holding the loop up
            return self._pool.submit(self._probe, server, seq, kinds, rates)
        except RuntimeError:    # pool shut down: the node is stopping
            return None

    def _request(self, server, seq, kinds, rates):
        stamp = rospy.Time.now()
        with self._lock:
            self._stamps[server] = (seq, stamp)
        # the nonce makes a sealed answer fit one request: without a key, none is drawn
        request = LatencyProbeRequest(robot_id=self.robot_id, seq=seq, stamp=stamp,
                                      nonce=self._nonce.getrandbits(64) if self._keyed else 0,
                                      task_kinds=kinds, task_rates=rates,
                                      node_uri=rospy.core.get_node_uri() or '')
        return self.seal.sign(server, request)

    def _then(self, server, seq, request, proxy):
        return lambda response, rtt, error: self._answered(server, seq, request, proxy,
                                                           response, rtt, error)

    def _after(self):
        if self.after_answers is not None:
            self.after_answers()

    def _probe(self, server, seq, kinds, rates):
        """A probe that connects first (a worker thread's). Whatever it raises ends the
        probe failed: its Future would keep the error unseen, and the robot, which probes
        a server again only once its probe out has ended, would never probe it again."""
        try:
            request = self._request(server, seq, kinds, rates)
            proxy = self._proxies.get(server)
            if proxy is None:       # removed meanwhile
                self.robot.probe_failed(server, seq, 'server left the fleet')
                return
            try:
                response, rtt = proxy.call_within(request, self.timeout)
            except rospy.ServiceException as error:
                self.robot.probe_failed(server, seq, str(error))
                return
            self._answered(server, seq, request, proxy, response, rtt, None)
        except Exception as failure:
            self._unhandled(server, seq, failure)
        finally:
            self._after()

    def _unhandled(self, server, seq, failure):
        """What a probe's own handling raised: logged (throttled), and the probe failed."""
        what = '%s: %s' % (type(failure).__name__, failure)
        rospy.logerr_throttle(5.0, 'robot %d: probe of server %d: %s' % (
            self.robot_id, server, what))
        self.robot.probe_failed(server, seq, 'probe not handled: %s' % what)

    def _answered(self, server, seq, request, proxy, response, rtt, error):
        """A probe's end: the robot hears of a failure, or of the answer once checked (what
        a check raises fails the probe: :meth:`_unhandled`)."""
        try:
            self._check(server, seq, request, proxy, response, rtt, error)
        except Exception as failure:
            self._unhandled(server, seq, failure)

    def _check(self, server, seq, request, proxy, response, rtt, error):
        if error is not None:
            self.seal.forget(server)    # a server started again knows it from a sealed one
            self.robot.probe_failed(server, seq, str(error))
            return
        if response.server_id != server or response.seq != seq:
            self.robot.probe_failed(server, seq, 'answer from server %d seq %d'
                                    % (response.server_id, response.seq))
            return
        forged = self.seal.forgery(server, response, proxy, request)
        if forged is not None:
            proxy.reconnect()       # to where the server's announcement says, once known
            self.robot.probe_failed(server, seq, 'answer not sealed by the fleet key: %s'
                                    % forged)
            return
        try:
            load = self.load_of(response) if self.load_of is not None else None
        except ValueError as bad:
            self.robot.probe_failed(server, seq, 'answer not understood: %s' % bad)
            return
        self.robot.probe_answered(server, seq, rtt, load)

    def sample(self, server, seq, rtt, error, wait, round_number):
        """A sample of the robot's: published, and added to its round's batch."""
        with self._lock:
            sent = self._stamps.pop(server) if self._stamps.get(server, (None,))[0] == seq \
                else None
            entry = self._rounds.get(round_number)
        batch = entry if isinstance(entry, ProbeRound) else None
        stamp = sent[1] if sent is not None else \
            batch.stamp if batch is not None else entry or rospy.Time.now()
        self.samples.sample(server, seq, stamp, rtt, error)
        if batch is not None and batch.record(server, not error, rtt, wait):
            with self._lock:
                self._rounds.pop(round_number, None)
            self.samples.round(batch)

    def shutdown(self):
        self._loop.stop()
        self._pool.shutdown(wait=False)
        with self._lock:
            proxies = list(self._proxies.values())
        for proxy in proxies:
            proxy.close()
