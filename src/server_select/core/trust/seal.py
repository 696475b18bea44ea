"""Signed fleet messages: an Ed25519 signature of the publisher's role over a message, its
publisher's name and where it travels (no rospy; the ROS side is
:mod:`server_select.ros.seal`).

In ROS 1 any process may register under any node name: a name check stops a careless node,
not one that takes the manager's name. With a fleet key (one secret file per fleet) the
fleet's advice and results carry a seal:
``mac = sign(role key, context, publisher name, seq, message)`` where ``context`` is the
topic (or service) name and the message type, ``message`` is the serialized message with
the MAC left empty, and ``seq`` is the publisher's clock in nanoseconds since the epoch,
strictly increasing per publisher.

**Roles.** Each role (:data:`ROLES`: the manager, servers, robots) signs with a key pair of
its own, derived from the fleet key (HKDF-SHA256 with the role's name: every node given
the fleet key derives the same), and :data:`PUBLISHERS` is the one table of which role may
publish which message type. A node given only its role's key file (``make_key --role``)
holds its role's private key and every role's public key: it checks everything, and signs
only as its role, so a robot's key cannot sign a flag, nor a server's a ranking. (With
signatures rather than a shared MAC key, what lets a node check a flag does not let it
make one.) A role's holders are not told apart from each other: any robot can sign as any
robot; the name check (the node a message must come from) remains.

A receiver with the keys admits a message only when

- its signature is right by a public key of a role that may publish its type (the current
  keys, or the next ones while keys are rotated), for the name of the node that published
  it and the topic it came on: a node without the key signs nothing, and a sealed message
  re-published under another name, or on another topic, fails;
- its ``seq`` is no older than ``max_age`` s by the receiver's clock (and no newer: clocks
  of the fleet's hosts agree within that), no older than the receiver's own start less
  :data:`START_SKEW` s, and has not been seen from that publisher before: a recorded
  message replayed later, a copy replayed at once, or one replayed to a receiver that
  restarted since it was sent, is refused. The last needs the fleet's clocks to agree
  within :data:`START_SKEW` s (NTP or chrony keep a LAN within milliseconds); latched
  messages older than the receiver are refused with it, and their publishers send them
  again every few seconds while a key is set.

What it does not do: hide anything (ROS 1 topics are plain TCP).
"""

import hashlib
import struct
import threading
import time

from server_select.core.trust.keys import (  # noqa: F401 (the key files, for the ROS side)
    OBSERVER, ROLES, KeyFileError, Keys, load_keys)

SIGNATURE_BYTES = 64      # an Ed25519 signature
START_SKEW = 2.0          # s: a message signed this much before its receiver started counts
CLOCK_STEP = 1.0          # s: a clock read this far behind the last sequence number stepped

# which role may sign which message type; any other sealed type is a task kind's result
# (kinds are plug-ins): servers'
PUBLISHERS = dict(('server_select/' + name, role) for role, names in (
    ('manager', ('SelectionFlag', 'FleetServers', 'GroupAssignments')),
    ('server', ('ServerAnnouncement', 'LatencyProbeResponse', 'Detections')),
    ('robot', ('LatencySample', 'LatencySamples', 'RobotRanking', 'TaskReport',
               'FoundTarget', 'LatencyProbeRequest')))
    for name in names)
RESULTS = 'server'


def publisher_role(msg_type):
    """The role that may sign messages of ``msg_type`` (``server_select/SelectionFlag``)."""
    return PUBLISHERS.get(msg_type, RESULTS)


def context(channel, msg_type):
    """What a seal binds a message to: the topic or service name it travels on, and its
    type (a copy replayed on another topic, or as another type, fails)."""
    return ('%s\0%s' % (channel, msg_type)).encode('utf-8')


def signed_digest(sender, seq, payload, where=b''):
    """What the signature covers: the SHA-256 digest of ``payload`` published by ``sender``
    with ``seq`` on ``where`` (:func:`context`). Signing the digest, not the message, costs
    one pass over a large message instead of Ed25519's two SHA-512 passes and a copy (a raw
    640x480 frame: 5.6 ms to seal and 4.9 ms to check, signed whole)."""
    digest = hashlib.sha256(where)
    for part in (b'\0', sender.encode('utf-8'), b'\0', struct.pack('<Q', seq), payload):
        digest.update(part)
    return digest.digest()


class Sealer(object):
    """The sending side: sequence numbers and signatures for one node (thread-safe), with
    ``keys`` (:class:`Keys` holding the private key of the node's role).

    A sequence number is this host's clock in ns, strictly increasing while the clock
    runs on; when the clock is stepped back by more than :data:`CLOCK_STEP` s (a Pi
    without a real-time clock that booted ahead, corrected by NTP), the numbers follow it
    back at once rather than counting on from the skewed time, which every receiver
    refused as from the future until the clock caught up."""

    def __init__(self, keys, sender, clock=time.time_ns):
        if keys.private is None:
            raise ValueError('a sealer needs a role to sign as')
        self.keys, self.sender, self._clock = keys, sender, clock
        self._lock = threading.Lock()
        self._last = 0

    def use(self, keys):
        """Sign with ``keys`` from now on (a key rotation): the sequence numbers go on."""
        if keys.private is None or keys.role != self.keys.role:
            raise ValueError('a sealer keeps its role (%s)' % self.keys.role)
        self.keys = keys

    def next_seq(self):
        """The publisher's clock in ns, strictly increasing but across a step back."""
        with self._lock:
            now = self._clock()
            stepped_back = now < self._last - int(CLOCK_STEP * 1e9)
            self._last = now if stepped_back else max(self._last + 1, now)
            return self._last

    def mac(self, seq, payload, where=b''):
        return self.keys.private.sign(signed_digest(self.sender, seq, payload, where)).signature


def _verifies(public, signature, data):
    from nacl.exceptions import BadSignatureError
    try:
        public.verify(data, signature)
        return True
    except BadSignatureError:
        return False


class Verifier(object):
    """The receiving side: whether a sealed message counts (thread-safe).

    ``keyrings``: the :class:`Keys` a signature may be made with (the current ones, and the
    next ones while keys are rotated). ``max_age``: s a message may be older (or newer) than
    this host's clock. Sequence numbers seen in the last ``max_age`` s are remembered per
    publisher; what was signed more than :data:`START_SKEW` s before this verifier was made
    (its node started, by this host's clock as it reads now: a step of the clock moves the
    start with it) is refused.
    """

    def __init__(self, keyrings, max_age=30.0, clock=time.time_ns,
                 monotonic=time.monotonic_ns):
        if not keyrings:
            raise ValueError('a verifier needs a key')
        self.keyrings, self.max_age_ns, self._clock = list(keyrings), int(max_age * 1e9), clock
        self._monotonic = monotonic
        self._started_mono = monotonic()
        self._lock = threading.Lock()
        self._seen = {}           # publisher -> {seq: True}, oldest first

    def use(self, keyrings):
        """Admit signatures made with ``keyrings`` from now on (a key rotation); the
        sequence numbers seen, and the start, stay (a replay stays one)."""
        if not keyrings:
            raise ValueError('a verifier needs a key')
        self.keyrings = list(keyrings)

    def _signer(self, mac_, data, role):
        """Whether ``role`` signed ``data``; else the role that did, or None."""
        mac_ = bytes(mac_)
        if len(mac_) != SIGNATURE_BYTES:
            return None
        keyrings = self.keyrings           # one set throughout, were it replaced meanwhile
        if any(_verifies(k.public[role], mac_, data) for k in keyrings):
            return role
        return next((r for r in ROLES if r != role and
                     any(_verifies(k.public[r], mac_, data) for k in keyrings)), None)

    def refusal(self, sender, seq, mac_, payload, where=b'', role='manager'):
        """None when the message counts (and its ``seq`` is now seen), else why not;
        ``role``: who may sign it (:func:`publisher_role` of its type)."""
        if not mac_:
            return 'not signed'
        signer = self._signer(mac_, signed_digest(sender, seq, payload, where), role)
        if signer is None:
            return 'wrong signature (another key, node, topic or type)'
        if signer != role:
            return 'signed with the %s key: only the %s role may publish it' % (signer, role)
        return self._stale(sender, seq)

    @property
    def started_ns(self):
        """When this verifier was made, by this host's clock now."""
        return self._clock() - (self._monotonic() - self._started_mono)

    def _stale(self, sender, seq):
        now = self._clock()
        if seq - now > self.max_age_ns:
            return 'this host\'s clock is %.1f s behind %s\'s: check NTP (messages count ' \
                'within %g s)' % ((seq - now) / 1e9, sender[:64], self.max_age_ns / 1e9)
        if now - seq > self.max_age_ns:
            return 'signed %.1f s before this host\'s clock (at most %g s): replayed, or ' \
                '%s\'s clock is behind this host\'s: check NTP' % (
                    (now - seq) / 1e9, self.max_age_ns / 1e9, sender[:64])
        if seq < self.started_ns - int(START_SKEW * 1e9):
            return 'signed %.1f s before this node started (replayed; the fleet\'s clocks ' \
                'must agree within %g s)' % ((self.started_ns - seq) / 1e9, START_SKEW)
        with self._lock:
            seen = self._seen.setdefault(sender, {})
            while seen:                          # forget what max_age refuses anyway
                oldest = next(iter(seen))
                if now - oldest <= self.max_age_ns:
                    break
                del seen[oldest]
            if seq in seen:
                return 'a copy of a message already received (replayed)'
            seen[seq] = True
        return None
