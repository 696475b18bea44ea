"""A LatencyProbe client whose calls give up after a deadline.

rospy's ServiceProxy has no call timeout: a call to a server that is hung (stopped,
overloaded, behind a dead link) blocks forever. :class:`TimedServiceProxy` keeps the
persistent connection of ``ServiceProxy(persistent=True)`` -- so a probe is one network
round trip, not a master lookup plus a TCP handshake -- and bounds every call:

- connecting (master lookup aside) uses the connect timeout rospy's transport offers;
- a call in progress at the deadline is aborted by closing its transport from a timer
  thread (``socket.shutdown`` wakes the blocked ``recv``), and the next call reconnects.
"""

import threading
import time

import rospy
from rospy.exceptions import ROSException, TransportInitError
from rospy.impl.tcpros_base import TCPROSTransport


class ProbeTimeout(rospy.ServiceException):
    """The call did not complete before its deadline."""


class TimedServiceProxy(rospy.ServiceProxy):
    """Persistent ``rospy.ServiceProxy`` with a per-call deadline (``call_within``)."""

    def __init__(self, name, service_class, pinned=None, on_moved=None):
        """``pinned()``: the address to connect to (None: the master's); ``on_moved(master,
        pinned)``: the master lists another address than the pinned one."""
        super(TimedServiceProxy, self).__init__(name, service_class, persistent=True)
        self.pinned, self.on_moved = pinned, on_moved
        self._abort_lock = threading.Lock()
        self._connecting = None
        self._aborted = False

    def call_within(self, request, timeout):
        """Call the service; return ``(response, seconds)`` of the request/response exchange.

        Raises ``rospy.ServiceException`` (``ProbeTimeout`` at the deadline) on failure;
        the connection is then dropped and re-established by the next call.
        """
        with self._abort_lock:
            self._aborted = False
        watchdog = threading.Timer(timeout, self._abort)
        watchdog.daemon = True
        watchdog.start()
        try:
            if self.transport is None:
                self._connect(request, timeout)
            start = time.perf_counter()
            response = self.call(request)
            elapsed = time.perf_counter() - start
            watchdog.cancel()
            with self._abort_lock:
                if self._aborted:  # the answer raced the deadline: the transport is closed
                    raise ProbeTimeout('answer arrived at the deadline of %.3g s' % timeout)
            return response, elapsed
        except (rospy.ServiceException, ROSException, OSError, AttributeError) as error:
            # AttributeError: rospy's transport torn down under a call by _abort().
            self._drop()
            if self._aborted:
                raise ProbeTimeout('no answer within %.3g s' % timeout)
            raise rospy.ServiceException(str(error) or type(error).__name__)
        finally:
            watchdog.cancel()

    def _connect(self, request, timeout):
        pinned = self.pinned() if self.pinned is not None else None
        try:
            uri = self._get_service_uri(request)  # master lookup; ServiceException if none
        except rospy.ServiceException:
            if pinned is None:
                raise
            uri = pinned
        if pinned is not None and uri != pinned:
            if self.on_moved is not None:
                self.on_moved(uri, pinned)
            uri = self.uri = pinned
        address, port = rospy.core.parse_rosrpc_uri(uri)
        transport = TCPROSTransport(self.protocol, self.resolved_name)
        transport.buff_size = self.buff_size
        with self._abort_lock:
            if self._aborted:
                raise ProbeTimeout('deadline passed during master lookup')
            self._connecting = transport
        try:
            transport.connect(address, port, uri, timeout=timeout)
        except TransportInitError as error:
            raise rospy.ServiceException('unable to connect to service: %s' % error)
        finally:
            with self._abort_lock:
                self._connecting = None
        self.transport = transport

    def _abort(self):
        with self._abort_lock:
            self._aborted = True
            transport = self._connecting or self.transport
        if transport is not None:
            transport.close()

    def reconnect(self):
        """Drop the connection: the next call connects again (to the pinned address)."""
        self._drop()

    def _drop(self):
        transport, self.transport = self.transport, None
        if transport is not None:
            transport.close()
