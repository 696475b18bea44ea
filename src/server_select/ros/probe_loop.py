"""One thread for a robot's probes: a round when the plan says, each answer as it comes.

Over an open connection a probe is a request written to a socket and an answer read from
it. :class:`ProbeLoop` waits on every socket with a probe out (``selectors``), on the
next round's time and on the earliest probe deadline at once, so a probe costs the robot
one wake-up for its answer instead of a worker thread's hand-off, a watchdog and a
blocked ``recv`` (bench-robot: on this host each wake-up of a thread costs about 0.1 ms).
A round trip runs from when the kernel sent the request to when it received the answer
(``SO_TIMESTAMPING``, ``SO_TIMESTAMPNS``: a robot busy with its own work, or a CPU share
that stalls it for a few scheduler ticks, does not add the time it took to get round to
writing the request or reading the answer); where the kernel gives no stamp, it starts
just before the request is written and ends when ``select`` returned. A probe that
needs a connection first (a master lookup, a TCP handshake, maybe to a host behind a dead
link) is not made here, where it would hold every other probe up: the prober hands those
to its worker threads.
"""

import selectors
import socket
import threading
import time

import rospy

from server_select.ros.probe_client import ProbeTimeout


class Flight(object):
    """A probe out on the loop: ``then(response, rtt, error)`` is called once; ``done()``
    says whether it has been (as a Future's)."""
    __slots__ = ('proxy', 'sock', 'started', 'sent', 'timeout', 'deadline', 'then',
                 'finished')

    def __init__(self, proxy, sock, started, timeout, then, sent=None):
        self.proxy, self.sock, self.started, self.timeout = proxy, sock, started, timeout
        self.sent = sent            # epoch s, to compare with the kernel's arrival stamp
        self.deadline = time.monotonic() + timeout
        self.then, self.finished = then, False

    def done(self):
        return self.finished

    def out_for(self):
        """Seconds the request has been out by the clock its round trip is measured with
        (from the kernel's send stamp, where there is one); 0.0 while its answer waits
        unread in the socket (the robot, not the link or the server, is behind)."""
        if self.sock is None or self.sent is None:
            return None
        try:    # bytes, not readiness: a send stamp come late polls ready too
            self.sock.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT)
            return 0.0              # answer bytes (or the server's close) wait unread
        except BlockingIOError:
            return time.time() - self.sent
        except OSError:             # closed meanwhile
            return None


class ProbeLoop(object):
    """Calls ``on_round()`` when ``next_time()`` comes (a ``time.monotonic`` time, None:
    no round due) and after :meth:`poke`; :meth:`start_probe` (from ``on_round``, on this
    thread) sends a request and ends it by its answer, an error or its deadline.
    ``on_error(exception)`` hears what ``on_round`` or a probe's ``then`` raised;
    ``after()`` is called once after each batch of probes that ended together."""

    def __init__(self, on_round, next_time, on_error, name='probe loop', after=None):
        self.on_round, self.next_time, self.on_error = on_round, next_time, on_error
        self.after = after or (lambda: None)
        self._selector = selectors.DefaultSelector()
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self._selector.register(self._wake_r, selectors.EVENT_READ, None)
        self._flights = {}       # socket -> Flight
        self._stopped = False
        self._last_round = float('-inf')
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def start(self):
        self._thread.start()

    def poke(self):
        """The plan changed: ask ``next_time`` again now."""
        try:
            self._wake_w.send(b'x')
        except (BlockingIOError, OSError):   # a wake-up is pending already, or stopped
            pass

    def stop(self):
        self._stopped = True
        self.poke()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(1.0)

    def start_probe(self, proxy, request, timeout, then):
        """Send ``request`` on ``proxy``'s open connection; ``then(response, rtt, error)``
        follows on this thread. Returns the Flight."""
        started, sent = time.perf_counter(), time.time()
        try:
            sock = proxy.send(request)
        except rospy.ServiceException as error:
            flight = Flight(proxy, None, started, timeout, then)
            self._finish(flight, None, None, error)
            return flight
        flight = Flight(proxy, sock, started, timeout, then, proxy.departed(sent) or sent)
        self._flights[sock] = flight
        try:
            self._selector.register(sock, selectors.EVENT_READ, flight)
        except KeyError:        # its number is that of a connection closed elsewhere (a
            self._forget_stale(sock.fileno())     # proxy renewed) while its probe was out
            self._selector.register(sock, selectors.EVENT_READ, flight)
        return flight

    def _forget_stale(self, fd):
        """The flight registered under ``fd`` lost its connection: ended, and its
        registration dropped (the number now belongs to a new connection)."""
        stale = self._selector.get_map().get(fd)
        if stale is None:
            return
        self._selector.unregister(stale.fileobj)
        if stale.data is not None and self._flights.pop(stale.fileobj, None) is not None:
            stale.data.finished = True
            try:
                stale.data.then(None, None, ProbeTimeout('its connection was closed'))
            except Exception as failure:    # the prober's bug must not stop the loop
                self.on_error(failure)

    def _finish(self, flight, response, rtt, error, drop=False):
        """``flight`` is over (``drop``: and its connection with it: an answer may still
        come, and must not be read as the next probe's)."""
        if flight.sock is not None and self._flights.pop(flight.sock, None) is not None:
            try:
                self._selector.unregister(flight.sock)
            except (KeyError, ValueError):   # dropped with a stale number already
                pass
        if drop:
            flight.proxy.reconnect()
        flight.finished = True
        try:
            flight.then(response, rtt, error)
        except Exception as failure:    # the prober's bug must not stop the loop
            self.on_error(failure)

    def _due(self):
        """The next round's time: ``next_time()``, and at least 1 ms after the last round
        (a plan that does not move on cannot make the loop spin)."""
        due = self.next_time()
        return None if due is None else max(due, self._last_round + 0.001)

    def _timeout(self):
        due = self._due()
        deadlines = [f.deadline for f in self._flights.values()]
        soonest = min([t for t in [due] + deadlines if t is not None], default=None)
        return None if soonest is None else max(0.0, soonest - time.monotonic())

    def _run(self):
        while not self._stopped:
            events = self._selector.select(self._timeout())
            received = time.perf_counter()       # the answers' round trips end here
            ended = len(self._flights)
            for key, _ in events:
                if key.data is None:
                    try:
                        self._wake_r.recv(4096)
                    except BlockingIOError:
                        pass
                    continue
                self._answer(key.data, received)
            now = time.monotonic()
            for flight in [f for f in self._flights.values() if f.deadline <= now]:
                self._finish(flight, None, None, ProbeTimeout(
                    'no answer within %.3g s' % flight.timeout), drop=True)
            if len(self._flights) < ended:
                self._call(self.after)
            due = self._due()
            if due is not None and time.monotonic() >= due and not self._stopped:
                self._last_round = time.monotonic()
                self._call(self.on_round)
        self._selector.close()
        self._wake_r.close()
        self._wake_w.close()

    def _call(self, function):
        try:
            function()
        except Exception as error:    # the prober's bug must not stop the loop
            self.on_error(error)

    def _answer(self, flight, received):
        if flight.finished:
            return
        try:
            answer = flight.proxy.read_answer()
        except rospy.ServiceException as error:
            self._finish(flight, None, None, error)
            return
        if answer is not None:
            response, arrived = answer
            rtt = arrived - flight.sent if arrived is not None else None
            if rtt is None or not 0.0 <= rtt <= received - flight.started + 1e-3:
                rtt = received - flight.started     # no stamp, or the wall clock stepped
            self._finish(flight, response, rtt, None)
