"""Signed fleet messages, the ROS side (:mod:`server_select.core.seal` has the rule).

A node with ``~fleet_key`` (a key file) seals what it publishes on the fleet's topics
(:class:`SealedPublisher`: flags, sample batches, task samples, server lists, group
assignments, task results) and admits those messages only when sealed with that key or
``~fleet_key_next`` (:func:`refusal`, called by every
:class:`~server_select.ros.senders.SenderGate`). Without ``~fleet_key`` nothing changes.
"""

import io
import threading

import rospy

from server_select.core import seal as core
from server_select.core.params import ParamError
from server_select.ros.node import param

_LOCK = threading.Lock()
_STATE = {}


def _configured():
    """(sealer, verifier) of this node, both None without ``~fleet_key``; read once (then
    without the lock: every gated message asks). :class:`ParamError` for a key file that
    cannot be used."""
    done = _STATE.get('done')
    if done is not None:
        return done
    with _LOCK:
        if 'done' not in _STATE:
            paths = dict((name, param(name)) for name in ('fleet_key', 'fleet_key_next'))
            if paths['fleet_key_next'] and not paths['fleet_key']:
                raise ParamError('~fleet_key_next: set ~fleet_key too (the key this node '
                                 'signs with)')
            keys = []
            for name, path in sorted(paths.items()):       # fleet_key first: it signs
                if path:
                    try:
                        keys.append(core.load_key(path))
                    except core.KeyFileError as error:
                        raise ParamError('~%s: %s' % (name, error))
            _STATE['done'] = (core.Sealer(keys[0], rospy.get_name()),
                              core.Verifier(keys, param('fleet_key_max_age'))) \
                if keys else (None, None)
        return _STATE['done']


def enabled():
    """Whether this node signs and checks fleet messages (reads the parameters on first
    use: call it at start-up, where a bad key file ends the node with one clear line)."""
    return _configured()[0] is not None


def _payload(msg):
    """What the MAC covers: ``msg`` serialized, but for ``header.seq``, which rospy's
    publisher numbers after the seal is made (the seal's own seq does its job)."""
    header = msg.header if getattr(msg.__class__, '_has_header', False) else None
    numbered = header.seq if header is not None else None
    if header is not None:
        header.seq = 0
    buf = io.BytesIO()
    try:
        msg.serialize(buf)
    finally:
        if header is not None:
            header.seq = numbered
    return buf.getvalue()


def seal(msg):
    """``msg`` with its seal made by this node (unchanged without a key, or when its type
    has no seal)."""
    return sealed(msg, _configured()[0])


def refusal(msg, sender):
    """None when ``msg`` (published by node ``sender``) counts for this node, else why not:
    without a key everything counts."""
    return check(msg, sender, _configured()[1])


def sealed(msg, sealer):
    """``msg`` sealed by ``sealer`` (a :class:`~server_select.core.seal.Sealer`; None:
    unchanged)."""
    if sealer is None or not hasattr(msg, 'seal'):
        return msg
    msg.seal.seq = sealer.next_seq()
    msg.seal.mac = b''
    msg.seal.mac = sealer.mac(msg.seal.seq, _payload(msg))
    return msg


def check(msg, sender, verifier):
    """``verifier``'s refusal of ``msg`` from ``sender`` (None: counts; so does everything
    when ``verifier`` is None)."""
    if verifier is None:
        return None
    stamp = getattr(msg, 'seal', None)
    if stamp is None:
        return 'its type has no seal'
    mac = stamp.mac
    stamp.mac = b''
    try:
        payload = _payload(msg)
    finally:
        stamp.mac = mac
    return verifier.refusal(sender, stamp.seq, mac, payload)


def require_sealable(msg_type, what):
    """With a key, refuse (ParamError) a message type that cannot carry a seal: its
    messages would all be refused."""
    if enabled() and 'seal' not in getattr(msg_type, '__slots__', ()):
        raise ParamError('~fleet_key: %s (%s) has no seal field: add "server_select/Seal '
                         'seal" to it, or run without a key' % (what, msg_type._type))


class SealedPublisher(rospy.Publisher):
    """A ``rospy.Publisher`` whose messages leave sealed with this node's key (as they are
    without one)."""

    def publish(self, msg):
        if not self.impl.is_latch and not self.impl.has_connections():
            return      # nobody listens: no seal to make (rospy would drop it too)
        super(SealedPublisher, self).publish(seal(msg))
