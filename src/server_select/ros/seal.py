"""Signed fleet messages, the ROS side (:mod:`server_select.core.trust.seal` has the rule).

A node with ``~fleet_key`` (a key file) seals what it publishes (:class:`SealedPublisher`)
and its probe answers (:func:`seal_answer`), and admits those only when sealed with that
key or ``~fleet_key_next`` on their topic or service (:func:`refusal`, called by every
:class:`~server_select.ros.senders.SenderGate`; :func:`answer_refusal`); :func:`reload_keys`
reads both files again. Without ``~fleet_key`` nothing is signed or checked: every node says
which at start (:func:`announce`), ``~require_key`` makes a missing key fatal, and a keyless
node that receives signed messages warns that it should have the key.
"""

import copy
import io
import threading

import rospy

from server_select.core.trust import seal as core
from server_select.core.config.params import ParamError
from server_select.core.trust.senders import Throttle
from server_select.ros.node import param

_LOCK = threading.Lock()
_STATE = {}


def _configured():
    """(sealer, verifier) of this node, both None without ``~fleet_key``; made once (then
    read without the lock: every gated message asks), ParamError for a key file that cannot
    be used. It signs as the role :func:`announce` was given (none: it only checks)."""
    done = _STATE.get('done')
    if done is not None:
        return done
    with _LOCK:
        if 'done' not in _STATE:
            paths = dict((name, param(name)) for name in ('fleet_key', 'fleet_key_next'))
            if paths['fleet_key_next'] and not paths['fleet_key']:
                raise ParamError('~fleet_key_next: set ~fleet_key too (the key this node '
                                 'signs with)')
            _STATE['paths'] = paths
            role, keys = _STATE.get('role'), _read_keys()
            sealer = core.Sealer(keys[0], rospy.get_name()) if keys and role else None
            _STATE['done'] = (sealer, core.Verifier(keys, param('fleet_key_max_age'))
                              if keys else None)
        return _STATE['done']


def _read_keys():
    """The keys in this node's key files, the one it signs with first (or ParamError)."""
    keys = []
    for name, path in sorted(_STATE['paths'].items()):       # fleet_key first: it signs
        if path:
            try:
                keys.append(core.load_keys(path, _STATE.get('role')))
            except core.KeyFileError as error:
                raise ParamError('~%s: %s' % (name, error))
    return keys


def reload_keys():
    """Sign and check with this node's key files read again (a rotation without a restart;
    seqs and replays seen stay): :func:`fingerprints` before and after. ParamError, the
    keys kept, when a file cannot be used or the node started without a key."""
    sealer, verifier = _configured()
    if verifier is None:
        raise ParamError('~fleet_key: this node started without a key: restart it with one')
    with _LOCK:         # one at a time: each caller gets the change its own call made
        before, keys = fingerprints(), _read_keys()
        if sealer is not None:
            sealer.use(keys[0])
        verifier.use(keys)
        return before, fingerprints()


def fingerprints():
    """(fingerprint of the key this node signs with or None, [of those it admits])."""
    sealer, verifier = _configured()
    return sealer and sealer.keys.fingerprint(), [k.fingerprint() for k in verifier.keyrings]


def announce(who, role=None):
    """One line at start: whether ``who`` (this node, publishing as ``role``, one of
    :data:`~server_select.core.trust.seal.ROLES`, or None when it publishes nothing sealed)
    signs and checks (``~require_key`` without a key: ParamError)."""
    _STATE['role'] = role
    if enabled():
        rospy.loginfo('%s: fleet key on: %s and counts only signed messages and probe '
                      'answers', who, 'signs what it publishes as the %s role' % role
                      if role else 'signs nothing (it publishes nothing sealed)')
    elif param('require_key'):
        raise ParamError('~require_key: no ~fleet_key given (make one with make_key and '
                         'give every node of the fleet a copy)')
    else:       # a warning where the fleet is deployed (once: by its manager), else a note
        log = rospy.logwarn if param('profile') == 'fleet' and role == 'manager' else \
            rospy.loginfo
        log('%s: fleet key off: signs nothing and checks nothing, so any node on this '
            'master can steer it (give every node ~fleet_key)', who)


_KEYLESS = Throttle(60.0)


def _keyless_heard(msg, sender):
    """A keyless node received a signed message: say once a minute what it lacks."""
    if getattr(getattr(msg, 'seal', None), 'mac', None):
        if _KEYLESS.due()[0]:
            rospy.logwarn('%s: received a signed %s from %s but has no ~fleet_key: it counts '
                          'unsigned messages too; give it the fleet\'s key (~fleet_key, or '
                          'fleet_key:= of its launch file)' % (rospy.get_name(), msg._type,
                                                               sender))


def enabled():
    """Whether this node checks (and, with a role, signs) fleet messages (call it at start:
    a bad key file then ends the node with one clear line)."""
    return _configured()[1] is not None


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


def seal(msg, channel):
    """``msg``, to go out on topic ``channel``, with its seal made by this node (unchanged
    without a key, or when its type has no seal)."""
    return sealed(msg, _configured()[0], channel)


def refusal(msg, sender):
    """None when ``msg`` (published by node ``sender``) counts for this node, else why not:
    without a key everything counts."""
    verifier = _configured()[1]
    if verifier is None:
        _keyless_heard(msg, sender)
        return None
    return check(msg, sender, verifier)


def sealed(msg, sealer, channel):
    """A copy of ``msg`` sealed by ``sealer`` (a
    :class:`~server_select.core.trust.seal.Sealer`; None: ``msg`` unchanged) for topic or
    service ``channel``. A copy: one message published on two topics keeps each topic's
    seal (a latched publisher keeps the object it was given, not its bytes)."""
    if sealer is None or not hasattr(msg, 'seal'):
        return msg
    msg = copy.copy(msg)
    msg.seal = copy.copy(msg.seal)
    msg.seal.seq = sealer.next_seq()
    msg.seal.mac = b''
    msg.seal.mac = sealer.mac(msg.seal.seq, _payload(msg), core.context(channel, msg._type))
    return msg


def check(msg, sender, verifier, channel=None):
    """``verifier``'s refusal of ``msg`` from ``sender`` (None: counts; so does everything
    when ``verifier`` is None), received on ``channel`` (None: the topic its connection
    says, as rospy keeps it)."""
    if verifier is None:
        return None
    stamp = getattr(msg, 'seal', None)
    if stamp is None:
        return 'its type has no seal'
    if not stamp.mac:
        return 'not signed'
    if channel is None:
        channel = (getattr(msg, '_connection_header', None) or {}).get('topic')
        if channel is None:
            return 'no topic known to check its seal against'
    mac = stamp.mac
    stamp.mac = b''
    try:
        payload = _payload(msg)
    finally:
        stamp.mac = mac
    return verifier.refusal(sender, stamp.seq, mac, payload, core.context(channel, msg._type),
                            core.publisher_role(msg._type))


def seal_answer(response, service, uri, request):
    """A probe answer of this node's ``service``, served at ``uri`` (its rosrpc address),
    sealed for ``request``: the robot, seq and nonce are in the seal (an answer fits one
    request only), and so is the address (an answer relayed by a node that registered the
    service at its own address fails). Unchanged without a key."""
    return sealed(response, _configured()[0], _answer_channel(service, uri, request))


def answer_refusal(response, service, uri, request, server_node):
    """None when a probe answer counts (no key here, or sealed with it by node
    ``server_node`` serving ``service`` at ``uri``, for this ``request``), else why not."""
    verifier = _configured()[1]
    if verifier is None:
        _keyless_heard(response, server_node)
        return None
    return check(response, server_node, verifier, _answer_channel(service, uri, request))


def request_refusal(request, service):
    """None when a probe ``request`` to this node's ``service`` is its robot's (no key
    here, or sealed with it by a robot, on this service, by the node that sent it), else
    why not."""
    verifier = _configured()[1]
    if verifier is None:
        return None
    sender = (getattr(request, '_connection_header', None) or {}).get('callerid', '')
    return check(request, sender, verifier, service)


def _answer_channel(service, uri, request):
    return '%s@%s#%d/%d/%d' % (service, uri, request.robot_id, request.seq, request.nonce)


def require_sealable(msg_type, what):
    """With a key, refuse (ParamError) a message type that cannot carry a seal: its
    messages would all be refused."""
    if enabled() and 'seal' not in getattr(msg_type, '__slots__', ()):
        raise ParamError('~fleet_key: %s (%s) has no seal field: add "server_select/Seal '
                         'seal" to it, or run without a key' % (what, msg_type._type))


class SealedPublisher(rospy.Publisher):
    """A ``rospy.Publisher`` whose messages leave sealed with this node's key (as they are
    without one). With a key, made only for a type the node's role may publish
    (:data:`~server_select.core.trust.seal.PUBLISHERS`; else ParamError)."""

    def __init__(self, name, data_class, *args, **kwargs):
        if 'seal' in getattr(data_class, '__slots__', ()) and enabled():
            sealer, role = _configured()[0], core.publisher_role(data_class._type)
            if sealer is None or sealer.keys.role != role:
                raise ParamError('~fleet_key: %s signs as %s, and only the %s role may '
                                 'publish %s' % (rospy.get_name(), 'the %s role' % sealer.keys
                                                 .role if sealer else 'no role', role,
                                                 data_class._type))
        super(SealedPublisher, self).__init__(name, data_class, *args, **kwargs)

    def publish(self, msg):
        if not self.impl.is_latch and not self.impl.has_connections():
            return      # nobody listens: no seal to make (rospy would drop it too)
        super(SealedPublisher, self).publish(seal(msg, self.resolved_name))
