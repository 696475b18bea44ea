"""A robot's probing of its servers: timed LatencyProbe calls when its probe plan says."""

import concurrent.futures
import itertools
import random
import threading
import time

import rospy

from server_select.core.config import names
from server_select.core.selection.answer_time import STILL_OUT, AnswerTimes
from server_select.core.selection.probing import ProbeRound
from server_select.ros.node import fleet
from server_select.ros.probe_client import TimedServiceProxy
from server_select.ros.probe_loop import Flight, ProbeLoop
from server_select.ros.probe_samples import ProbeSamples
from server_select.ros.probe_seal import ProbeSeal
from server_select.ros.seal import enabled as keyed
from server_select.srv import LatencyProbe, LatencyProbeRequest


class Prober(object):
    """Probes the servers when ``plan`` (a ``ProbePlan``) says, a round when its next time
    comes, and publishes each sample, failed ones too. ``contenders``, for adaptive plans,
    is the robot's ``Selection``, whose ``contenders()`` (its rule's) the plan takes each
    round.

    Probes go out on one loop thread over persistent connections (a probe that must
    connect first, on a worker thread), each bounded by ``timeout``; a server whose
    previous probe is still out is not probed again, and once that probe is late for this
    server (``AnswerTimes``: twice its longest recent answer) it gets a failed sample
    (:data:`STILL_OUT`): a link down is known by the next probe, a busy server on a small
    CPU share is given the time its answers take. Samples go out as
    ``stream`` says (``ProbeSamples``; ``view``: for recorders, the manager hears the
    robot's own ranking). Servers can be added and removed at run time. ``answered``:
    the servers that have answered at least once; ``on_sample(server, ok, rtt, error,
    wait)`` hears every sample.
    With ``load_of``, each answer's load goes to ``load_of(server, response, rtt)``, which
    returns the *wait* at that server (s; None: unknown), carried in the sample and the
    batch; ``announce(server)`` gives the ``(task kinds, rates)`` a probe of it carries.
    ``node_of(server, refresh)`` names the node the master says serves its probe service:
    with a fleet key an answer counts only when sealed by that node, for this request, at
    the address probed (``seal.answer_refusal``); any other is a failed probe and a
    throttled warning naming who answered. ``addresses`` (a ``ProbeAddresses``, with a
    key): each server is probed at the address, and checked against the node, that its
    sealed announcement names, whatever the master lists.
    """

    def __init__(self, robot_id, servers, plan, timeout, on_sample=None, stream='pair',
                 load_of=None, announce=None, contenders=None, node_of=None, addresses=None):
        self.robot_id = robot_id
        self.plan, self.contenders = plan, contenders
        self.timeout = timeout
        self.answered = set()
        self.on_sample = on_sample or (lambda server, ok, rtt, error, wait: None)
        self.load_of = load_of
        self.announce = announce
        self.seal = ProbeSeal(robot_id, node_of, addresses)
        self._nonce, self._keyed = random.SystemRandom(), keyed()
        self._seq = itertools.count(1)
        self._rounds = itertools.count(1)
        self._lock = threading.Lock()
        self._inflight = {}          # server -> (its probe's future, when it went out)
        self.answer_times = AnswerTimes()
        self._proxies = {}
        self.samples = ProbeSamples(robot_id, stream, load_of is not None)
        self._pool = concurrent.futures.ThreadPoolExecutor(
            max_workers=max(16, len(servers)), thread_name_prefix='probe')
        self.after_answers = None    # called once after each batch of samples
        self._loop = ProbeLoop(self.on_round, self._next_time, self._on_error,
                               after=self._after)
        self._first = 0.0
        for server in servers:
            self.add(server)

    @property
    def servers(self):
        with self._lock:
            return sorted(self._proxies)

    def add(self, server):
        with self._lock:
            if server in self._proxies:
                return
            self.samples.add(server)
            self._proxies[server] = TimedServiceProxy(
                fleet(names.probe_service(server)), LatencyProbe, *self.seal.proxy_args(server))
            self.plan.add(server, time.monotonic())
        self._loop.poke()

    def remove(self, server):
        with self._lock:
            proxy = self._proxies.pop(server, None)
            self.answered.discard(server)
            self.plan.remove(server)
        if proxy is not None:
            proxy.close()
        self.samples.remove(server)
        self.answer_times.forget(server)

    def start(self):
        # the first round one period after the start, as the paper's timer had it (servers
        # started with the robot register their services meanwhile)
        self._first = time.monotonic() + self.plan.tick
        self._loop.start()

    def _next_time(self):
        with self._lock:
            due = self.plan.next_time()
        return None if due is None else max(due, self._first)

    def _on_error(self, error):
        rospy.logerr_throttle(5.0, 'robot %d: probing: %s: %s' % (
            self.robot_id, type(error).__name__, error))

    def on_round(self):
        """Probe the servers the plan says are due (one round)."""
        if rospy.is_shutdown():
            self._loop.stop()
            return
        contenders, task_rate = (self.contenders.contenders(), self.contenders.task_rate()) \
            if self.contenders is not None else ((), None)
        with self._lock:
            now = time.monotonic()
            self.plan.update(contenders, now, task_rate)
            servers = [s for s in self.plan.due(now) if not self._out(s, now)]
        if not servers:
            return
        stamp = rospy.Time.now()
        batch = ProbeRound(next(self._rounds), stamp, servers) if self.samples.batched else None
        for server in servers:
            if self._out(server, None):    # and late: a failed sample, no second call
                self._publish(server, next(self._seq), stamp, None, STILL_OUT, batch)
                continue
            seq, proxy = next(self._seq), self._proxies.get(server)
            if proxy is not None and proxy.connected():     # on the loop: one wake-up
                sent, request = self._request(server, seq)
                future = self._loop.start_probe(
                    proxy, request, self.timeout, self._then(server, seq, sent, request,
                                                             proxy, batch))
            else:       # a connection first: on a worker thread, not holding the loop up
                try:
                    future = self._pool.submit(self._probe, server, seq, batch)
                except RuntimeError:  # pool shut down: the node is stopping
                    return
            self._inflight[server] = (future, now)

    def _out(self, server, now):
        """Whether ``server``'s previous probe is still out (with ``now``: and not late
        yet, so that this round leaves it out)."""
        previous, sent = self._inflight.get(server, (None, 0.0))
        if previous is None or previous.done():
            return False
        if now is None:
            return True
        # by the clock of its round trips: from the kernel's send stamp, and not late
        # while its answer waits unread (a probe connecting first: from the round's time)
        out_for = previous.out_for() if isinstance(previous, Flight) else None
        return not self.answer_times.late(server, now - sent if out_for is None else out_for)

    def _request(self, server, seq):
        stamp = rospy.Time.now()
        # the nonce makes a sealed answer fit one request: without a key, none is drawn
        request = LatencyProbeRequest(robot_id=self.robot_id, seq=seq, stamp=stamp,
                                      nonce=self._nonce.getrandbits(64) if self._keyed else 0)
        if self.announce is not None:
            request.task_kinds, request.task_rates = self.announce(server)
        return stamp, self.seal.sign(server, request)

    def _then(self, server, seq, stamp, request, proxy, batch):
        return lambda response, rtt, error: self._answered(server, seq, stamp, request, proxy,
                                                           batch, response, rtt, error)

    def _after(self):
        if self.after_answers is not None:
            self.after_answers()

    def _probe(self, server, seq, batch):
        """A probe that connects first (a worker thread's)."""
        try:
            self._probe_connecting(server, seq, batch)
        finally:
            self._after()

    def _probe_connecting(self, server, seq, batch):
        stamp, request = self._request(server, seq)
        proxy = self._proxies.get(server)
        if proxy is None:       # removed meanwhile
            self._publish(server, seq, stamp, None, 'server left the fleet', batch)
            return
        try:
            response, rtt = proxy.call_within(request, self.timeout)
        except rospy.ServiceException as error:
            self._publish(server, seq, stamp, None, str(error), batch)
            return
        self._answered(server, seq, stamp, request, proxy, batch, response, rtt, None)

    def _answered(self, server, seq, stamp, request, proxy, batch, response, rtt, error):
        """A probe's end: a failed sample, or the answer checked and its sample."""
        if error is not None:
            self.seal.forget(server)    # a server started again knows it from a sealed one
            self._publish(server, seq, stamp, None, str(error), batch)
            return
        if response.server_id != server or response.seq != seq:
            self._publish(server, seq, stamp, None, 'answer from server %d seq %d'
                          % (response.server_id, response.seq), batch)
            return
        forged = self.seal.forgery(server, response, proxy, request)
        if forged is not None:
            proxy.reconnect()       # to where the server's announcement says, once known
            self._publish(server, seq, stamp, None, 'answer not sealed by the fleet key: %s'
                          % forged, batch)
            return
        self.answered.add(server)
        self.answer_times.answered(server, rtt)
        wait = self.load_of(server, response, rtt) if self.load_of is not None else None
        self._publish(server, seq, stamp, rtt, '', batch, wait)

    def _publish(self, server, seq, stamp, rtt, error, batch, wait=None):
        self.samples.sample(server, seq, stamp, rtt, error)
        self.on_sample(server, not error, rtt, error, wait)
        if batch is not None and batch.record(server, not error, rtt, wait):
            self.samples.round(batch)

    def shutdown(self):
        self._loop.stop()
        self._pool.shutdown(wait=False)
        with self._lock:
            proxies = list(self._proxies.values())
        for proxy in proxies:
            proxy.close()
