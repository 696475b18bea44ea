"""Which answers to a robot's probes are its servers' own, by the fleet key (a part of
the :class:`~server_select.ros.prober.Prober`)."""

import rospy

from server_select.core.trust.senders import Throttle
from server_select.ros import seal


class ProbeSeal(object):
    """``node_of(server, refresh)`` names the node the master says serves a server's probe
    service; ``addresses`` (a :class:`~server_select.ros.membership.ProbeAddresses`, with a
    key, or None) the address and node its sealed announcement names, which win."""

    def __init__(self, robot_id, node_of=None, addresses=None):
        self.robot_id, self.addresses = robot_id, addresses
        self.node_of = node_of or (lambda server, refresh=False: None)
        self._forged = Throttle(5.0)

    def proxy_args(self, server):
        """What a server's TimedServiceProxy is given: its pinned address and what to do
        when the master lists another (nothing without announced addresses)."""
        return (self._pinned(server), self._moved(server)) if self.addresses else ()

    def _pinned(self, server):
        return lambda: (self.addresses.of(server) or (None, None))[0]

    def _moved(self, server):
        def warn(master, pinned):
            due, held = self._forged.due()
            if due:
                rospy.logwarn('robot %d: the master lists %s for the probe service of server '
                              '%d, but the server\'s sealed announcement says %s: probing '
                              'that (another node registered the service)%s' % (
                                  self.robot_id, master, server, pinned,
                                  '; %d more before' % held if held else ''))
        return warn

    def node(self, server, refresh=False):
        """The node whose seal a probe answer of ``server`` must carry."""
        announced = self.addresses.of(server) if self.addresses is not None else None
        return announced[1] if announced else self.node_of(server, refresh)

    def forgery(self, server, response, proxy, request):
        """Why the answer is not the server's, by the fleet key (None: it is, or no key)."""
        if not seal.enabled():
            return None     # no key: nothing to check, no node to look up
        node = self.node(server)
        forged = seal.answer_refusal(response, proxy.resolved_name, proxy.uri, request,
                                     node or '?')
        if forged is not None and not forged.endswith('(replayed)'):
            node = self.node(server, True)         # the server may have been restarted
            forged = seal.answer_refusal(response, proxy.resolved_name, proxy.uri, request,
                                         node or '?')
        if forged is not None:
            due, held = self._forged.due()
            if due:
                rospy.logwarn('robot %d: ignored a probe answer of %s from node %s at %s '
                              '(%s, by the fleet key): not server %d%s' % (
                                  self.robot_id, proxy.resolved_name, node, proxy.uri, forged,
                                  server, '; %d more before' % held if held else ''))
        return forged
