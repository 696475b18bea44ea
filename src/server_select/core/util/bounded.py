"""What a peer may make a node keep or print, bounded (no rospy): a name a peer gives
itself (a callerid, an address) is cut before it goes into a log line or an error, and a
table by peer keeps its most recently counted entries only. A peer that makes up a new
900 KB name per connection costs a line of 64 characters and one of a few hundred entries.
"""

import collections
import collections.abc

PEER_CHARS = 64         # characters of a peer's name kept in a line or a table key
PEER_ENTRIES = 256      # peers a table by peer keeps


def peer(name, most=PEER_CHARS):
    """``name`` (what a peer calls itself) in at most about ``most`` characters: a longer
    one as its start and its length."""
    name = str(name)
    if len(name) <= most:
        return name
    tail = '...(%d chars)' % len(name)
    return name[:max(8, most - len(tail))] + tail


class PeerCounter(collections.abc.Mapping):
    """Counts by peer (its name cut by :func:`peer`), at most ``most`` peers: the least
    recently counted go first; ``total`` counts them all."""

    def __init__(self, most=PEER_ENTRIES):
        self.most, self.total = int(most), 0
        self._counts = collections.OrderedDict()

    def add(self, name, count=1):
        """Count ``count`` for peer ``name``; returns its count now."""
        key = peer(name)
        value = self._counts.pop(key, 0) + count
        self._counts[key] = value
        while len(self._counts) > self.most:
            self._counts.popitem(last=False)
        self.total += count
        return value

    def __getitem__(self, name):
        return self._counts[peer(name)]

    def __iter__(self):
        return iter(self._counts)

    def __len__(self):
        return len(self._counts)
