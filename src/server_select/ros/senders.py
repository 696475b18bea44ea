"""The one gate every callback that checks who published a message goes through."""

import rospy

from server_select.core.trust.senders import ExpectedSender, Throttle
from server_select.core.util.bounded import PEER_CHARS, peer
from server_select.ros import seal
from server_select.ros.graph import Liveness, publisher_of


class SenderGate(object):
    """Admits a message only from the node that should send it
    (:class:`~server_select.core.trust.senders.ExpectedSender`); anything else is dropped with a
    warning naming the publisher, at most one every ``period`` s for this gate.

    ``who`` starts the warning (``robot 1``), ``role`` names the expected node in it
    (``the manager``, ``server {key}``, ``robot {key}``).
    """

    def __init__(self, who, role, expected=None, lookup=None, within=False, period=5.0,
                 hint=None, alive=None):
        """``hint(sender, key)``: the fix to name when ``sender`` is refused (or None);
        ``alive``: keys are claimed (ExpectedSender)."""
        self.who, self.role, self.hint = who, role, hint
        self.rule = ExpectedSender(expected, lookup, within, alive)
        self.throttle = Throttle(period)

    def expect(self, expected):
        """From now on messages count from ``expected`` (a resolved name; None: any)."""
        self.rule.expected = expected

    def admits(self, msg, what, key=None):
        """Whether ``msg`` counts: from the expected node and, with a fleet key, sealed
        with it (:func:`server_select.ros.seal.refusal`). ``what`` it is, for the warning:
        a string, or a function making it (then only made for a refused message: results
        and samples are a hot path)."""
        sender = publisher_of(msg)
        unsealed = seal.refusal(msg, sender)     # first: an unsigned message claims nothing
        if unsealed is not None:
            self._warn(what, sender, '%s, by the fleet key' % unsealed)
            return False
        expected = self.rule.refusal(sender, key)
        if expected is not None:
            fix = self.hint(sender, key) if self.hint is not None else None
            self._warn(what, sender, '%s is %s%s%s' % (
                self.role.format(key=key), expected,
                ' or a node in its namespace' if self.rule.within else '',
                '; %s' % fix if fix else ''))
            return False
        return True

    def _warn(self, what, sender, why):
        due, held = self.throttle.due()
        if due:
            what = what() if callable(what) else what
            rospy.logwarn('%s: ignored %s published by %s (%s)%s' % (
                self.who, what, peer(sender), peer(why, 4 * PEER_CHARS),
                '; %d more ignored before' % held if held else ''))


def warn(throttle, text):
    """``text`` as a warning when ``throttle`` (a Throttle) says one is due, with how many
    were held back since the last."""
    due, held = throttle.due()
    if due:
        rospy.logwarn(text + ('; %d more before' % held if held else ''))


def node_pattern(pattern):
    """``lookup(id, refresh)`` of ExpectedSender for a node name pattern with ``{id}``
    (``/robot{id}``), resolved in the caller's namespace once per id."""
    names = {}

    def lookup(key, _refresh):
        name = names.get(key)
        if name is None:
            name = names[key] = rospy.resolve_name(pattern.format(id=key))
        return name
    return lookup


FIRST = 'first'         # ~robot_node: a robot is the first node that sends for its id


def robot_senders(who, pattern, hint=None):
    """The gate of robots' messages: robot ``{key}`` is the node ``pattern`` names
    (``/robot{id}``), or with :data:`FIRST` the first node that sent for it while that node
    answers (:class:`~server_select.ros.graph.Liveness`), or any node (None). Without a
    fleet key nodes in its namespace count too; with one, only the node itself (any node
    may take a name in a robot's namespace)."""
    within = not seal.enabled()
    if pattern == FIRST:
        return SenderGate(who, 'robot {key}', within=within, alive=Liveness())
    return SenderGate(who, 'robot {key}', within=within,
                      lookup=node_pattern(pattern) if pattern else None, hint=hint)
