"""Signed fleet messages: an HMAC-SHA256 seal over a message and its publisher's name (no
rospy; the ROS side is :mod:`server_select.ros.seal`).

In ROS 1 any process may register under any node name: a name check stops a careless node,
not one that takes the manager's name. With a fleet key (one secret file per fleet) the
fleet's advice and results carry a seal:
``mac = HMAC(key, context, publisher name, seq, message)`` where ``context`` is the topic
(or service) name and the message type, ``message`` is the serialized message with the MAC
left empty, and ``seq`` is the publisher's clock in nanoseconds since the epoch, strictly
increasing per publisher. A receiver with the key admits a message only when

- its MAC is right for one of the receiver's keys (the current one, or the next one while
  keys are rotated), the name of the node that published it and the topic it came on: a
  node without the key signs nothing, and a sealed message re-published under another
  name, or on another topic, fails;
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

import argparse
import hashlib
import hmac
import os
import stat
import struct
import threading
import time

KEY_BYTES = 32            # what make_key writes
MIN_KEY_BYTES = 16
MAC_BYTES = hashlib.sha256().digest_size
START_SKEW = 2.0          # s: a message signed this much before its receiver started counts


class KeyFileError(ValueError):
    """A key file that cannot be used (named, with what to do)."""


def make_key(path, random=os.urandom):
    """Write a new key (``KEY_BYTES`` random bytes, hex) to ``path``, readable by its owner
    only; refuses to overwrite a file."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, 'w') as stream:
        stream.write(random(KEY_BYTES).hex() + '\n')


def load_key(path):
    """The key in ``path`` (hex text, as :func:`make_key` writes it). Refused
    (:class:`KeyFileError`) when missing, readable or writable by group or others, not hex, or
    shorter than ``MIN_KEY_BYTES``."""
    try:
        mode = os.stat(path).st_mode
        with open(path) as stream:
            text = stream.read().strip()
    except OSError as error:
        raise KeyFileError('cannot read fleet key %s: %s' % (path, error.strerror))
    if mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise KeyFileError('fleet key %s can be read or written by others (mode %03o): '
                           'chmod 600 %s' % (path, stat.S_IMODE(mode), path))
    try:
        key = bytes.fromhex(text)
    except ValueError:
        raise KeyFileError('fleet key %s is not hex text (make one with make_key)' % path)
    if len(key) < MIN_KEY_BYTES:
        raise KeyFileError('fleet key %s has %d bytes, fewer than %d'
                           % (path, len(key), MIN_KEY_BYTES))
    return key


def context(channel, msg_type):
    """What a seal binds a message to: the topic or service name it travels on, and its
    type (a copy replayed on another topic, or as another type, fails)."""
    return ('%s\0%s' % (channel, msg_type)).encode('utf-8')


def mac(key, sender, seq, payload, where=b''):
    """The seal's MAC of ``payload`` (bytes) published by node ``sender`` with ``seq`` on
    ``where`` (:func:`context`)."""
    head = where + b'\0' + sender.encode('utf-8') + b'\0' + struct.pack('<Q', seq)
    return hmac.new(key, head + payload, hashlib.sha256).digest()


class Sealer(object):
    """The sending side: sequence numbers and MACs for one node (thread-safe)."""

    def __init__(self, key, sender, clock=time.time_ns):
        self.key, self.sender, self._clock = key, sender, clock
        self._lock = threading.Lock()
        self._last = 0

    def next_seq(self):
        """The publisher's clock in ns, strictly increasing."""
        with self._lock:
            self._last = max(self._last + 1, self._clock())
            return self._last

    def mac(self, seq, payload, where=b''):
        return mac(self.key, self.sender, seq, payload, where)


class Verifier(object):
    """The receiving side: whether a sealed message counts (thread-safe).

    ``keys``: the keys a MAC may be made with (the current one, and the next one while
    keys are rotated). ``max_age``: s a message may be older (or newer) than this host's
    clock. Sequence numbers seen in the last ``max_age`` s are remembered per publisher;
    what was signed more than :data:`START_SKEW` s before this verifier was made (its
    node started) is refused.
    """

    def __init__(self, keys, max_age=30.0, clock=time.time_ns):
        if not keys:
            raise ValueError('a verifier needs a key')
        self.keys, self.max_age_ns, self._clock = list(keys), int(max_age * 1e9), clock
        self.started_ns = clock()
        self._lock = threading.Lock()
        self._seen = {}           # publisher -> {seq: True}, oldest first

    def refusal(self, sender, seq, mac_, payload, where=b''):
        """None when the message counts (and its ``seq`` is now seen), else why not."""
        if not mac_:
            return 'not signed'
        if not any(hmac.compare_digest(mac(k, sender, seq, payload, where), bytes(mac_))
                   for k in self.keys):
            return 'wrong signature (another key, node, topic or type)'
        now = self._clock()
        if abs(now - seq) > self.max_age_ns:
            return 'signed %.1f s %s this host\'s clock (at most %g s: replayed, or clocks ' \
                'apart)' % (abs(now - seq) / 1e9, 'before' if seq < now else 'after',
                            self.max_age_ns / 1e9)
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


def make_key_cli(argv=None):
    """``make_key FILE``: a new fleet key in FILE (mode 0600; an existing file is kept)."""
    parser = argparse.ArgumentParser(
        prog='make_key', description='Write a new fleet key (%d random bytes, hex) to FILE, '
        'readable by its owner only. Give every node of the fleet a copy (~fleet_key, or '
        'fleet_key:= of the launch files).' % KEY_BYTES)
    parser.add_argument('file')
    args = parser.parse_args(argv)
    try:
        make_key(args.file)
    except OSError as error:
        parser.exit(1, 'make_key: %s: %s\n' % (args.file, error.strerror))
    print('fleet key written to %s (mode 0600)' % args.file)
    return 0
