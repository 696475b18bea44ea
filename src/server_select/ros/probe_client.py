"""A LatencyProbe client whose calls give up after a deadline.

rospy's ServiceProxy has no call timeout: a call to a server that is hung (stopped,
overloaded, behind a dead link) blocks forever. :class:`TimedServiceProxy` keeps the
persistent connection of ``ServiceProxy(persistent=True)`` -- so a probe is one network
round trip, not a master lookup plus a TCP handshake -- and bounds every call:

- connecting asks the master where the service is with a deadline of its own (rospy's
  lookup has none: a starved master held a probe's worker thread past every deadline)
  and uses the connect timeout rospy's transport offers;
- a call in progress at the deadline is aborted by closing its transport from the
  node's one watchdog thread (``socket.shutdown`` wakes the blocked ``recv``), and the
  next call reconnects. (A ``threading.Timer`` per call started a thread per probe: 160 us
  of CPU each on this host, six times the 27 us of the call itself.)
"""

import socket
import struct
import threading
import time

import xmlrpc.client

import genpy
import rosgraph
import rospy
from rospy.exceptions import ROSException, TransportInitError
from rospy.impl.validators import ParameterInvalid
from rospy.impl.tcpros_base import TCPROSTransport

from server_select.core.util.pacer import Watchdog
from server_select.ros import graph

DEADLINES = Watchdog(name='probe deadlines')      # every proxy's calls, one thread
SO_TIMESTAMPNS = 35     # Linux <asm-generic/socket.h>; Python's socket module lacks them
SO_TIMESTAMPING = 37
# <linux/net_tstamp.h>: a software stamp of each send as it leaves the stack, on the error
# queue, without the packet
TX_STAMPS = (1 << 1) | (1 << 4) | (1 << 11)     # TX_SOFTWARE | SOFTWARE | OPT_TSONLY
# an answer's ancillary data: SO_TIMESTAMPNS's timespec, then SO_TIMESTAMPING's three
STAMP_SPACE = socket.CMSG_SPACE(16) + socket.CMSG_SPACE(48)


def stamp_packets(sock):
    """Ask the kernel to stamp each packet ``sock`` receives (SO_TIMESTAMPNS) and sends
    (SO_TIMESTAMPING): a probe's round trip then runs from when its request left to when
    its answer arrived, not from when a busy robot got round to writing it to when it got
    round to reading the answer. Returns ``(received, sent)``: whether each is stamped
    (False where the option is refused)."""
    stamped = []
    for option, value in ((SO_TIMESTAMPNS, 1), (SO_TIMESTAMPING, TX_STAMPS)):
        try:
            sock.setsockopt(socket.SOL_SOCKET, option, value)
            stamped.append(True)
        except OSError:
            stamped.append(False)
    return tuple(stamped)


def arrival(ancillary):
    """The kernel's receive time (epoch s) in recvmsg's ``ancillary`` data, or None."""
    for level, kind, data in ancillary:
        if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS and len(data) >= 16:
            seconds, nanoseconds = struct.unpack('qq', data[:16])
            return seconds + nanoseconds * 1e-9
    return None


def departures(sock, until=None):
    """The send stamps (epoch s) waiting on ``sock``'s error queue, oldest first; reading
    them empties the queue (left there, they would make the socket poll ready and take
    its receive buffer). With ``until``, the reading stops at the first stamp not before
    it, a request's own: the rest, if any, are read at the next call, and a probe does not
    pay for the read of an empty queue, which raises."""
    stamps = []
    while not stamps or until is None or stamps[-1] < until:
        try:
            _data, ancillary, _flags, _address = sock.recvmsg(
                0, 512, socket.MSG_ERRQUEUE | socket.MSG_DONTWAIT)
        except OSError:           # BlockingIOError: the queue is empty
            return stamps
        for level, kind, data in ancillary:
            if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPING and len(data) >= 16:
                seconds, nanoseconds = struct.unpack('qq', data[:16])     # ts[0]: software
                stamps.append(seconds + nanoseconds * 1e-9)
    return stamps


class ProbeTimeout(rospy.ServiceException):
    """The call did not complete before its deadline."""


def lookup_service(name, timeout):
    """The ``rosrpc://`` URI the master lists for service ``name``, asked with a deadline of
    ``timeout`` s. ServiceException when it is not listed, ProbeTimeout when the master
    does not answer in time."""
    try:
        uri = graph.service_uri(name, rospy.get_caller_id(), max(0.001, timeout))
        rospy.core.parse_rosrpc_uri(uri)
        return uri
    except socket.timeout:
        raise ProbeTimeout('the master did not say where %s is within %.3g s' % (name, timeout))
    except (OSError, xmlrpc.client.Error, rosgraph.MasterError, ParameterInvalid) as error:
        raise rospy.ServiceException('master lookup of %s: %s' % (
            name, str(error) or type(error).__name__))


class TimedServiceProxy(rospy.ServiceProxy):
    """Persistent ``rospy.ServiceProxy`` with a per-call deadline (``call_within``)."""

    def __init__(self, name, service_class, pinned=None, on_moved=None):
        """``pinned()``: the address to connect to (None: the master's); ``on_moved(master,
        pinned)``: the master lists another address than the pinned one."""
        super(TimedServiceProxy, self).__init__(name, service_class, persistent=True)
        self.pinned, self.on_moved = pinned, on_moved
        self._abort_lock = threading.Lock()
        self._connecting = None
        self._stamps = (False, False)   # the connection's packets carry the kernel's stamp
        self._aborted = False

    def call_within(self, request, timeout):
        """Call the service; return ``(response, seconds)`` of the request/response exchange.

        Raises ``rospy.ServiceException`` (``ProbeTimeout`` at the deadline) on failure;
        the connection is then dropped and re-established by the next call.
        """
        with self._abort_lock:
            self._aborted = False
        watchdog = DEADLINES.arm(timeout, self._abort)
        try:
            if self.transport is None:
                self._connect(request, timeout)
            start = time.perf_counter()
            response = self.call(request)
            elapsed = time.perf_counter() - start
            DEADLINES.cancel(watchdog)
            self.departed()                # this call's send stamps are of no use here
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
            DEADLINES.cancel(watchdog)

    # -- a call in two halves, for one thread that waits on many sockets (ProbeLoop) ---------

    def connected(self):
        """Whether a connection is up (a call then needs no master lookup nor handshake)."""
        transport = self.transport
        return transport is not None and transport.socket is not None and not transport.done

    def send(self, request):
        """Send ``request`` on the open connection; returns its socket, to be polled for
        the answer (:meth:`read_answer`; :meth:`departed` says when it left).
        ServiceException (the connection dropped) if it cannot be sent."""
        transport = self.transport
        try:
            self.seq += 1
            transport.send_message(request, self.seq)
            return transport.socket
        except (ROSException, OSError, AttributeError) as error:
            self._drop()
            raise rospy.ServiceException(str(error) or type(error).__name__)

    def departed(self, after=0.0):
        """When the last request sent left this robot (the kernel's stamp, epoch s), if it
        is known and not before ``after``; else None."""
        transport = self.transport
        if not self._stamps[1] or transport is None or transport.socket is None:
            return None
        stamps = [t for t in departures(transport.socket, after) if t >= after]
        return stamps[-1] if stamps else None

    def read_answer(self):
        """After the socket polled readable: ``(response, arrived)`` once the response is
        whole (``arrived``: when the kernel received its last bytes, epoch s, or None where
        it does not say), else None. ServiceException (the connection then dropped) on an
        error answer or a closed connection."""
        transport = self.transport
        try:
            try:
                data, ancillary, _flags, _address = transport.socket.recvmsg(
                    transport.protocol.buff_size, STAMP_SPACE if self._stamps[0] else 0,
                    socket.MSG_DONTWAIT)
            except (BlockingIOError, InterruptedError):
                if self._stamps[1]:
                    departures(transport.socket)    # a send stamp come late: polled ready
                return None
            if not data:
                raise rospy.ServiceException('the server closed the connection')
            transport.read_buff.write(data)
            answers = []
            transport.protocol.read_messages(transport.read_buff, answers, transport.socket)
            return (answers[0], arrival(ancillary)) if answers else None
        except (rospy.ServiceException, ROSException, OSError, AttributeError,
                genpy.DeserializationError) as error:
            self._drop()
            raise rospy.ServiceException(str(error) or type(error).__name__)

    def _connect(self, request, timeout):
        pinned = self.pinned() if self.pinned is not None else None
        try:
            uri = self.uri = lookup_service(self.resolved_name, timeout)
        except rospy.ServiceException:     # not listed (taken by another node and left)
            if pinned is None:
                raise
            uri = self.uri = pinned    # the address an answer's seal is checked against
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
        self._stamps = stamp_packets(transport.socket)     # once per connection
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
