"""Simulated robots for the scale benchmark: samples in bulk, flags watched (one process).

Robots ``first .. first+count-1`` each send one probe round a second for servers
``1..servers`` (``--layout robot``: one ``latency_samples`` batch; ``pair``: one
``latency_R<r>S<s>`` sample per server), with round trips that give every robot a
different, well separated nearest server. Once every robot of this process has a flag
ranking all servers, one robot every ``--change-every`` s gets a 10 s round trip for the
server its flag selects, which must move its flag elsewhere: the time from that sample's
publication to the flag that shows the move is the sample-to-flag delay. Results go to
``--out`` as JSON.
"""

import argparse
import json
import random
import threading
import time

import rospy

from server_select.core import names
from server_select.msg import LatencySample, LatencySamples, SelectionFlag

SLOW = 10.0
QUIET = 7.0       # s between two triggers of one robot (window 5 s + margin)


def base_rtt(robot, server, servers):
    """Robot ``robot``'s nearest server is the one with (robot + server) % servers == 0."""
    return 1e-3 * (1 + (robot + server) % servers)


class SimulatedRobots(object):
    def __init__(self, robots, servers, layout, change_every):
        self.robots, self.servers, self.layout = robots, servers, layout
        self.change_every = change_every
        self.lock = threading.Lock()
        self.ranked = {}             # robot -> time its first full ranking arrived
        self.flagged = {}            # robot -> server its last flag selected
        self.triggers = {}           # robot -> (publication time, server made slow)
        self.last_trigger = {}       # robot -> when: its slow sample leaves the window after
        #                              5 s and moves the flag back; no trigger meanwhile
        self.delays = []
        self.flags = 0
        self.rng = random.Random(robots[0])
        self.sub = rospy.Subscriber(names.SELECTION_TOPIC, SelectionFlag, self.on_flag,
                                    queue_size=10000, tcp_nodelay=True)
        if layout == 'robot':
            self.pub = rospy.Publisher(names.SAMPLES_TOPIC, LatencySamples, queue_size=10000)
        else:
            self.pubs = dict(((r, s), rospy.Publisher(names.sample_topic(r, s), LatencySample,
                                                      queue_size=100))
                             for r in robots for s in range(1, servers + 1))

    def on_flag(self, flag):
        now = time.time()
        robot = flag.robot_id
        if robot not in self.robots:
            return
        with self.lock:
            self.flags += 1
            if len(flag.ranking) == self.servers and robot not in self.ranked:
                self.ranked[robot] = now
            trigger = self.triggers.get(robot)
            if trigger is not None and flag.server_id != trigger[1]:
                self.delays.append(now - trigger[0])
                del self.triggers[robot]
            self.flagged[robot] = flag.server_id

    def send(self, robot, slow=None, sending=lambda: None):
        """One probe round of ``robot``; ``sending()`` right before the ``slow`` sample goes."""
        servers = list(range(1, self.servers + 1))
        if slow is not None:                      # the slow sample first
            servers.remove(slow)
            servers.insert(0, slow)
        rtts = [SLOW if s == slow else base_rtt(robot, s, self.servers) +
                2e-4 * self.rng.random() for s in servers]     # noise below the 1 ms steps
        if self.layout == 'robot':
            msg = LatencySamples(robot_id=robot, server_id=servers, ok=[True] * len(rtts),
                                 rtt=rtts)
            msg.header.stamp = rospy.Time.now()
            sending()
            self.pub.publish(msg)
            return
        for server, rtt in zip(servers, rtts):
            if server == slow:
                sending()
            self.pubs[(robot, server)].publish(LatencySample(robot_id=robot, server_id=server,
                                                             ok=True, rtt=rtt))

    def all_ranked(self):
        with self.lock:
            return len(self.ranked) == len(self.robots)

    def trigger(self, robot):
        with self.lock:
            slow = self.flagged.get(robot)
            quiet = time.time() - self.last_trigger.get(robot, 0.0) > QUIET
            if slow is None or slow < 1 or robot in self.triggers or not quiet:
                return
            self.last_trigger[robot] = time.time()

        def sending():
            with self.lock:
                self.triggers[robot] = (time.time(), slow)
        self.send(robot, slow, sending)

    def run(self, until):
        period = 1.0 / len(self.robots)
        next_change = None
        index = 0
        while time.time() < until and not rospy.is_shutdown():
            robot = self.robots[index % len(self.robots)]
            index += 1
            self.send(robot)
            if next_change is None and self.all_ranked():
                next_change = time.time() + 2.0
            if next_change is not None and time.time() >= next_change:
                self.trigger(self.robots[self.rng.randrange(len(self.robots))])   # if quiet
                next_change += self.change_every
            time.sleep(period)

    def result(self):
        with self.lock:
            return {'ranked': self.ranked, 'delays': self.delays, 'flags': self.flags,
                    'robots': len(self.robots)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--first', type=int, required=True)
    parser.add_argument('--count', type=int, required=True)
    parser.add_argument('--servers', type=int, required=True)
    parser.add_argument('--layout', choices=('robot', 'pair'), required=True)
    parser.add_argument('--until', type=float, required=True, help='epoch s to stop at')
    parser.add_argument('--change-every', type=float, default=0.5)
    parser.add_argument('--out', required=True)
    args = parser.parse_args(argv)
    rospy.init_node('scale_sim_%d' % args.first, disable_signals=True)
    sim = SimulatedRobots(list(range(args.first, args.first + args.count)), args.servers,
                          args.layout, args.change_every)
    sim.run(args.until)
    with open(args.out, 'w') as stream:
        json.dump(sim.result(), stream)
    rospy.signal_shutdown('done')


if __name__ == '__main__':
    main()
