"""Who may publish what a node takes: the one rule behind every check of a message's
publisher (no rospy; the ROS side is :class:`server_select.ros.senders.SenderGate`).

In ROS 1 a subscriber hears every publisher of its topic. The fleet's messages count only
from the node that should send them: a flag from the manager, a result from the node that
serves the server's probe service, samples of robot ``r`` from the node known as robot
``r`` (or a node in its namespace): by default the first node that sent for ``r`` while it
lives, whatever its name (a robot is known by the id it announces; with a fleet key only
a robot's key can announce one).
"""

import collections
import re
import threading
import time


def owned_by(node, owner):
    """Whether ``node`` is ``owner`` or a node inside ``owner``'s namespace."""
    return node == owner or node.startswith(owner.rstrip('/') + '/')


class ExpectedSender(object):
    """The node whose messages count, for each key (a robot, a server; None when there is
    one for all), and whether ``sender`` is it.

    ``expected`` is a resolved node name, or None: any node counts. ``lookup(key, refresh)``
    instead names the node of a key (None: unknown, any counts); a message from another
    node makes it look once more with ``refresh=True`` (the node may have been restarted
    elsewhere). ``alive(node)`` instead makes the first node that sends for a key that
    key's node (a claim) until ``alive`` says it is gone, when the next sender's claim
    counts. ``within``: a node in the expected node's namespace counts too.
    """

    def __init__(self, expected=None, lookup=None, within=False, alive=None):
        if sum(x is not None for x in (expected, lookup, alive)) > 1:
            raise ValueError('give expected, lookup or alive, not two')
        self.expected, self.lookup, self.within = expected, lookup, within
        self.alive = alive
        self._claims = {}          # key -> the node that claimed it
        self._lock = threading.Lock()

    def _matches(self, sender, expected):
        return expected is None or (owned_by(sender, expected) if self.within
                                    else sender == expected)

    def refusal(self, sender, key=None):
        """None when ``sender``'s message counts, else the node that should have sent it."""
        if self.alive is not None:
            return self._claim(sender, key)
        if self.lookup is None:
            return None if self._matches(sender, self.expected) else self.expected
        expected = self.lookup(key, False)
        if self._matches(sender, expected):
            return None
        expected = self.lookup(key, True)
        return None if self._matches(sender, expected) else expected

    def _claim(self, sender, key):
        with self._lock:
            owner = self._claims.setdefault(key, sender)
        if self._matches(sender, owner):
            return None
        if self.alive(owner):
            return owner
        with self._lock:             # gone: this sender's claim counts from now on
            if self._claims.get(key) == owner:
                self._claims[key] = sender
        return None


def node_pattern_of(sender, key):
    """The ``~robot_node`` pattern that would admit ``sender`` as robot ``key``: its name
    with each number equal to the key written ``{id}`` (``/tb3_2/robot2``, 2:
    ``/tb3_{id}/robot{id}``); None when no number in it is the key."""
    parts = re.split(r'(\d+)', sender)
    if str(key) not in parts[1::2]:
        return None
    return ''.join('{id}' if i % 2 and part == str(key) else part
                   for i, part in enumerate(parts))


class Throttle(object):
    """At most one line a ``period``: :meth:`due` says whether to write one now and how
    many were held back since the last (thread-safe)."""

    def __init__(self, period=5.0, clock=time.monotonic):
        self.period, self._clock = period, clock
        self._lock = threading.Lock()
        self._last = None
        self._held = 0

    def due(self):
        """``(write now, lines held back before this one)``."""
        with self._lock:
            now = self._clock()
            if self._last is not None and now - self._last < self.period:
                self._held += 1
                return False, 0
            held, self._held, self._last = self._held, 0, now
            return True, held


class SenderThrottle(object):
    """At most one line a ``period`` for each sender, and ``lines`` a ``period`` in all:
    one sender's lines (a robot answered busy now and then) do not hide another's (a robot
    flooding the server), and senders under made-up names cannot flood the log. The
    ``most`` latest senders are remembered. :meth:`due` says whether to write a line for
    ``sender`` now and how many of its lines were held back since its last (thread-safe)."""

    def __init__(self, period=5.0, lines=4, most=64, clock=time.monotonic):
        self.period, self.lines, self.most, self._clock = period, lines, most, clock
        self._lock = threading.Lock()
        self._senders = collections.OrderedDict()   # sender -> [its last line or None, held]
        self._written = collections.deque()         # when the last lines were written

    def due(self, sender):
        """``(write now, lines of ``sender`` held back before this one)``."""
        with self._lock:
            now = self._clock()
            entry = self._senders.pop(sender, None) or [None, 0]
            self._senders[sender] = entry
            while len(self._senders) > self.most:
                self._senders.popitem(last=False)
            while self._written and now - self._written[0] >= self.period:
                self._written.popleft()
            if entry[0] is not None and now - entry[0] < self.period or \
                    len(self._written) >= self.lines:
                entry[1] += 1
                return False, 0
            held, entry[:] = entry[1], [now, 0]
            self._written.append(now)
            return True, held
