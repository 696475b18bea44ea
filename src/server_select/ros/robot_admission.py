"""Which node is which robot, at a server with a fleet key: the probes say.

ROS 1 lets any node publish a task under any robot id, and name rates in a probe. With a
fleet key a robot seals a probe request (robot role) when what it announces changes, and
once a second; a sealed probe binds its robot id to the node that sent it for
:data:`ROBOT_LEASE` s, renewed by each (another node's claim meanwhile is refused; a robot
restarted under another name is bound again once the old lease ends). Only a bound
robot's sealed probes announce rates and prepare its result topics, and only its node's
tasks are taken; the others are dropped unanswered (an answer to a made-up robot costs a
publisher), counted by sender, in a line at most every 5 s that also says how many tasks
were taken meanwhile. Without a key everything counts.
"""

import threading

import rospy

from server_select.core.fleet.leases import Leases
from server_select.core.trust.senders import Throttle
from server_select.core.util.bounded import PEER_CHARS, PeerCounter, peer
from server_select.ros import seal
from server_select.ros.graph import publisher_of
from server_select.ros.senders import warn

ROBOT_LEASE = 10.0       # s a signed probe binds its robot id (robots probe every ~0.5 s)


class RobotAdmission(object):
    """A server's binding of robot ids to nodes (:meth:`probe`) and the gate of its tasks
    (:meth:`admits`); ``who`` names it in the log. Thread-safe."""

    def __init__(self, who, service, clock=None):
        self.who, self.service = who, service
        self.keyed = seal.enabled()
        self._clock = clock or rospy.get_time
        self.leases = Leases()
        self._lock = threading.Lock()
        self._expired_at = 0.0
        self.taken = 0
        self.refused = PeerCounter()      # sender -> tasks dropped (the latest senders)
        self._probe_throttle, self._task_throttle = Throttle(5.0), Throttle(5.0)

    def probe(self, request):
        """Whether ``request`` is its robot's own (then it binds the robot id to its node):
        True without a key; an observer's (robot 0) binds nothing."""
        if not self.keyed:
            return True
        if request.robot_id == 0:
            return False
        sender = (getattr(request, '_connection_header', None) or {}).get('callerid', '?')
        if not request.seal.mac and self.leases.holder(request.robot_id, self._clock()) == sender:
            return False          # its robot's, between the ones it seals (once a second)
        why = seal.request_refusal(request, self.service)
        if why is None:
            now = self._clock()
            self._expire(now)
            _changed, holder = self.leases.renew(request.robot_id, sender, now, ROBOT_LEASE)
            if holder is None:
                return True
            why = 'robot %d is %s\'s until its probes stop for %g s' % (
                request.robot_id, holder, ROBOT_LEASE)
        warn(self._probe_throttle, '%s: a probe of robot %d from %s announces nothing and '
             'prepares nothing (%s, by the fleet key)'
             % (self.who, request.robot_id, peer(sender), peer(why, 4 * PEER_CHARS)))
        return False

    def _expire(self, now):
        with self._lock:
            if now - self._expired_at < 1.0:
                return
            self._expired_at = now
        self.leases.expire(now)

    def admits(self, task):
        """Whether ``task`` comes from the node its robot id is bound to (always without a
        key)."""
        if not self.keyed:
            return True
        sender = publisher_of(task)
        bound = self.leases.holder(task.robot_id, self._clock())    # a lease ends in time
        with self._lock:
            if bound is not None and sender == bound:
                self.taken += 1
                return True
            refused, taken = self.refused.add(sender), self.taken
        sender = peer(sender)
        warn(self._task_throttle, '%s: dropped a task of robot %d from %s (%s): %d of its '
             'tasks dropped, %d robots\' tasks taken so far'
             % (self.who, task.robot_id, sender, 'no signed probe of robot %d' % task.robot_id
                if bound is None else 'robot %d is %s' % (task.robot_id, bound), refused,
                taken))
        return False
