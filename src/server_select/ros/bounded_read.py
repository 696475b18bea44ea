"""What this node reads from a connection is bounded before it is read.

rospy reads a whole connection header, and a whole message, into memory before anything
can look at it: a header claiming 4 GB makes it copy its buffer on every read, a 40 MB task
is stored, deserialized and queued before its kind can refuse it. Both are preceded by a
4-byte length, checked here first (the way gRPC checks ``max_receive_message_length``):

- :func:`install` (every node, at start): a connection header longer than
  :data:`MAX_HEADER_BYTES` ends its connection, read no further.
- :func:`limit` (a topic this node subscribes to, a service it serves): a message longer
  than the limit is read past without being kept (the connection stays usable for the
  sender's next message), counted by sender, and named in a line at most every 5 s.
- every other subscription to one of the fleet's own message types has its type's limit
  (:mod:`server_select.core.config.limits`, docs/parameters.md): an announcement of
  150 MB is refused from its length, not read, decoded and then refused for its seal.
"""

import socket
import struct
import threading

import rospy
from rosgraph.network import ROSHandshakeException, decode_ros_handshake_header
from rospy.impl import tcpros_base
from rospy.impl.tcpros_pubsub import TCPROSSub
from rospy.impl.tcpros_service import TCPService

from server_select.core.config.limits import MESSAGE_LIMITS
from server_select.core.trust.senders import Throttle
from server_select.core.util.bounded import PeerCounter, peer

MAX_HEADER_BYTES = 1 << 20    # the fleet's largest header is 5 KB (ImageResult's definition)
_SCRATCH = 1 << 16            # read size while reading past a refused message
_LIMITS = {}                  # resolved topic or service name -> largest message, bytes
_LOCK = threading.Lock()
_REFUSED = PeerCounter()      # 'sender on name' -> messages refused (the latest senders)
_THROTTLE = Throttle(5.0)
_ORIGINAL = {}


def _recv_exactly(sock, count, held=0):
    """``count`` bytes from ``sock``; ``held`` were read before (for the message)."""
    chunks = []
    while count:
        chunk = sock.recv(min(count, _SCRATCH))
        if not chunk:       # rosgraph's words (a node's log filter knows the usual case)
            raise ROSHandshakeException(
                'connection from sender terminated before handshake header received. %d '
                'bytes were received. Please check sender for additional details.'
                % (held + sum(map(len, chunks))))
        chunks.append(chunk)
        count -= len(chunk)
    return b''.join(chunks)


def read_header(sock, buffer, _buff_size, most=MAX_HEADER_BYTES):
    """rosgraph's ``read_ros_handshake_header`` with the header's length checked before it
    is read (ROSHandshakeException naming the peer and the limit); bytes after the header
    stay in ``buffer``, as there."""
    held = buffer.getvalue()
    if len(held) < 4:
        held += _recv_exactly(sock, 4 - len(held), len(held))
    (size,) = struct.unpack('<I', held[:4])
    if size > most:
        try:
            peer = '%s:%d' % sock.getpeername()[:2]
        except (OSError, TypeError):
            peer = 'an unknown peer'
        raise ROSHandshakeException('connection header of %d bytes from %s refused: more '
                                    'than %d' % (size, peer, most))
    if len(held) < size + 4:
        held += _recv_exactly(sock, size + 4 - len(held), len(held))
    buffer.seek(0)
    buffer.truncate()
    buffer.write(held[size + 4:])
    return decode_ros_handshake_header(held[:size + 4])


def limit(name, most):
    """Messages on ``name`` (a resolved topic this node subscribes to or a service it
    serves) longer than ``most`` bytes are refused unread."""
    install()
    with _LOCK:
        _LIMITS[name] = int(most)


def refused():
    """Messages refused so far, by ``'sender on topic or service'`` (the latest senders'),
    and in all."""
    with _LOCK:
        return dict(_REFUSED), _REFUSED.total


def _length(buffer):
    with buffer.getbuffer() as view:
        return struct.unpack_from('<I', view)[0]


def _read_past(transport, size):
    """Drop the message of ``size`` bytes at the start of the transport's buffer, reading
    from its socket what has not arrived yet into a scratch buffer."""
    buffer, sock = transport.read_buff, transport.socket
    held = buffer.tell()
    with buffer.getbuffer() as view:
        rest = bytes(view[size + 4:held]) if held > size + 4 else b''
    missing = max(0, size + 4 - held)
    scratch = bytearray(_SCRATCH)
    while missing:
        got = sock.recv_into(scratch, min(missing, _SCRATCH))
        if not got:
            raise tcpros_base.TransportTerminated('closed inside a refused message')
        missing -= got
    buffer.seek(0)
    buffer.truncate()
    buffer.write(rest)


def _refuse(transport, name, size, most):
    """Count and name the message just read past; a service client is answered with the
    reason (its call fails at once, with it)."""
    sender = peer((transport.header or {}).get('callerid', 'an unknown node'))
    why = 'a message of %d bytes on %s from %s: more than its limit of %d' % (
        size, name, sender, most)
    if isinstance(transport.protocol, TCPService):
        error = ('request refused: %s' % why).encode('utf-8')
        transport.write_data(struct.pack('<BI', 0, len(error)) + error)
    with _LOCK:
        _REFUSED.add('%s on %s' % (sender, name))
        total = _REFUSED.total
    due, held = _THROTTLE.due()
    if due:
        rospy.logwarn('%s: refused %s%s' % (
            rospy.get_name(), why, ' (%d refused in all)' % total if held else ''))


def _limit_of(protocol):
    """The largest message ``protocol`` takes: its topic's or service's limit, else its
    message type's (None: none)."""
    most = _LIMITS.get(getattr(protocol, 'resolved_name', None))
    if most is None and isinstance(protocol, TCPROSSub):
        most = MESSAGE_LIMITS.get(getattr(protocol.recv_data_class, '_type', None))
    return most


def _receive_once(transport):
    """rospy's, but a message over its topic's limit is read past and refused first
    (then nothing is returned: rospy's loops ask again)."""
    protocol = transport.protocol
    most = _limit_of(protocol)
    if most is not None and isinstance(protocol, (TCPROSSub, TCPService)) and \
            transport.socket is not None:
        buffer = transport.read_buff
        try:
            transport.socket.setblocking(1)
            while buffer.tell() < 4:
                tcpros_base.recv_buff(transport.socket, buffer, protocol.buff_size)
            size = _length(buffer)
            if size > most:
                _read_past(transport, size)
                _refuse(transport, protocol.resolved_name, size, most)
                return []
        except socket.error as error:
            raise tcpros_base.TransportException('receive_once[%s]: %s'
                                                 % (transport.name, error))
    return _ORIGINAL['receive_once'](transport)


def _whole_within(buffer, most):
    """How many whole messages start the buffer before the first one longer than
    ``most`` (None: no such message has begun in it)."""
    held = buffer.tell()
    count = pos = 0
    with buffer.getbuffer() as view:
        while pos + 4 <= held:
            size = struct.unpack_from('<I', view, pos)[0]
            if size > most:
                return count
            if pos + 4 + size > held:
                break
            count, pos = count + 1, pos + 4 + size
    return None


def _read_messages(protocol, buffer, msg_queue, sock):
    """rospy's, but a message over the limit in the same buffer as good ones is not
    deserialized with them: it stays at the buffer's start for :func:`_receive_once`."""
    most = _limit_of(protocol)
    whole = _whole_within(buffer, most) if most is not None else None
    if whole == 0:
        return
    tcpros_base.deserialize_messages(buffer, msg_queue, protocol.recv_data_class,
                                     queue_size=protocol.queue_size, max_msgs=whole)


def install():
    """Bound every connection header this node reads, and make :func:`limit` effective
    (idempotent)."""
    with _LOCK:
        if _ORIGINAL:
            return
        _ORIGINAL['receive_once'] = tcpros_base.TCPROSTransport.receive_once
        _ORIGINAL['read_header'] = tcpros_base.read_ros_handshake_header
        tcpros_base.TCPROSTransport.receive_once = _receive_once
        tcpros_base.read_ros_handshake_header = read_header
        for protocol in (TCPROSSub, TCPService):     # (their base's, shared with others)
            protocol.read_messages = _read_messages
