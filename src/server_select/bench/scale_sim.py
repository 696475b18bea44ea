"""Simulated robots for the scale benchmark: samples in bulk, flags watched (one process).

Robots ``first .. first+count-1`` each send ``--rate`` probe rounds a second (1) for servers
``1..servers`` (``--layout robot``: one ``latency_samples`` batch; ``pair``: one
``latency_R<r>S<s>`` sample per server; ``view``: the robot's own ranking of them on
``robot_rankings``, as a fleet-profile robot sends it at ``~view_rate``), with round trips
that give every robot a different, well separated nearest server (a view also says a
wait of 0 for each, as load-aware robots with idle servers do: a server made slow is
slower on the network, and the manager moves the robot at once). Once every robot of
this process has a flag
ranking all servers, one robot every ``--change-every`` s gets a 10 s round trip for the
server its flag selects, which must move its flag elsewhere: the time from that sample's
publication to the flag that shows the move is the sample-to-flag delay. Results go to
``--out`` as JSON, rewritten every half second while it runs (so the benchmark can wait for
"every robot ranked" and "a change measured"); it runs until SIGINT / SIGTERM or ``--until``.
``--flag-stream robot``: each robot hears its own ``robot_<r>/server_select_flag``, as a
fleet-profile robot does; ``shared``: every robot hears ``server_select_flag`` (each flag
of every robot). The flags and their bytes that would reach the robots are counted.

``--layout grouped``: the servers form ``--groups`` equal groups; each robot follows the
top manager's ``group_assignments`` and sends batches for its group's servers plus every
group's representative, as a grouped robot does; a full ranking is then one of all its
group's servers, from its group's manager.
"""

import argparse
import io
import json
import os
import random
import signal
import threading
import time

import rospy

from server_select.core.config import names
from server_select.bench.scale_layout import base_rtt, group_table
from server_select.core.fleet.groups import probe_set
from server_select.core.trust.seal import Sealer, load_keys
from server_select.msg import (GroupAssignments, LatencySample, LatencySamples, RobotRanking,
                               SelectionFlag)
from server_select.ros.seal import sealed

SLOW = 10.0
QUIET = 7.0       # s between two triggers of one robot: its slow sample leaves the window
#                   after 5 s (the paper; the fleet's 1.5 s) and moves the flag back
SETTLED = 4.0     # s since a robot's flag last changed before it is triggered: a policy with
#                   a dwell (the fleet's 3 s) holds a move that soon after the last, by design


class SimulatedRobots(object):
    def __init__(self, robots, servers, layout, change_every, groups=1, sealer=None,
                 flag_stream='shared'):
        self.robots, self.servers, self.layout = robots, servers, layout
        self.sealer = sealer         # a fleet key's Sealer: samples leave signed
        self.change_every, self.groups = change_every, groups
        self.table = group_table(servers, groups)
        self.probed = dict((r, sorted(probe_set(self.table, None))) for r in robots) \
            if layout == 'grouped' else None
        self.group_of = {}
        self.lock = threading.Lock()
        self.ranked = {}             # robot -> time its first full ranking arrived
        self.flagged = {}            # robot -> server its last flag selected
        self.triggers = {}           # robot -> (publication time, server made slow)
        self.last_trigger = {}       # robot -> when it was last triggered (QUIET)
        self.changed = {}            # robot -> when its flag last changed (SETTLED)
        self.delays, self.flags = [], 0
        # flags that reached the robots, their bytes; a flag's bytes on the wire
        self.received, self.size = [0, 0], 0
        self.rng = random.Random(robots[0])
        # a shared topic reaches the process once; each robot's node would get it alone
        topics, self.copies = ([names.SELECTION_TOPIC], len(robots)) if flag_stream == \
            'shared' else ([names.robot_topic(r, names.SELECTION_TOPIC) for r in robots], 1)
        self.subs = [rospy.Subscriber(topic, SelectionFlag, self.on_flag, queue_size=10000,
                                      tcp_nodelay=True) for topic in topics]
        if layout == 'grouped':
            self.groups_sub = rospy.Subscriber(names.GROUPS_TOPIC, GroupAssignments,
                                               self.on_groups, queue_size=10)
        if layout == 'view':
            self.pub = rospy.Publisher(names.RANKINGS_TOPIC, RobotRanking, queue_size=10000)
        elif layout in ('robot', 'grouped'):
            self.pub = rospy.Publisher(names.SAMPLES_TOPIC, LatencySamples, queue_size=10000)
        else:
            self.pubs = dict(((r, s), rospy.Publisher(names.sample_topic(r, s), LatencySample,
                                                      queue_size=100))
                             for r in robots for s in range(1, servers + 1))

    def on_groups(self, msg):
        with self.lock:
            for robot, group in zip(msg.robot_id, msg.group_id):
                if robot in self.probed:
                    self.group_of[robot] = group
                    self.probed[robot] = sorted(probe_set(self.table, group))

    def full(self, robot):
        """How many servers a full ranking of ``robot`` has."""
        if self.layout != 'grouped':
            return self.servers
        group = self.group_of.get(robot)
        return len(self.table[group]) if group else -1

    def on_flag(self, flag):
        now = time.time()
        robot = flag.robot_id
        with self.lock:
            if self.received[0] % (50 * self.copies) == 0:    # one flag in 50 measured
                buf = io.BytesIO()
                flag.serialize(buf)
                self.size = len(buf.getvalue()) + 4    # + TCPROS's length prefix
            self.received[0] += self.copies
            self.received[1] += self.copies * self.size
            if robot not in self.robots:
                return
            self.flags += 1
            if len(flag.ranking) == self.full(robot) and robot not in self.ranked:
                self.ranked[robot] = now
            trigger = self.triggers.get(robot)
            if trigger is not None and flag.server_id != trigger[1]:
                self.delays.append(now - trigger[0])
                del self.triggers[robot]
            if flag.server_id != self.flagged.get(robot):
                self.changed[robot] = now
            self.flagged[robot] = flag.server_id

    def send(self, robot, slow=None, sending=lambda: None):
        """One probe round of ``robot``; ``sending()`` right before the ``slow`` sample goes."""
        with self.lock:
            servers = list(self.probed[robot]) if self.probed else \
                list(range(1, self.servers + 1))
        if slow is not None and slow in servers:  # the slow sample first
            servers.remove(slow)
            servers.insert(0, slow)
        noise = 2e-4 if self.groups == 1 else 2e-5           # below the steps
        rtts = [SLOW if s == slow else base_rtt(robot, s, self.servers, self.groups) +
                noise * self.rng.random() for s in servers]
        if self.layout != 'pair':
            if self.layout == 'view':   # the robot's own ranking, as a robot sends it
                order = sorted(range(len(servers)), key=lambda i: rtts[i])
                msg = RobotRanking(robot_id=robot, ranking=[servers[i] for i in order],
                                   mean_latency=[rtts[i] for i in order],
                                   error=[noise] * len(order), sample_count=[3] * len(order),
                                   wait=[0.0] * len(order))
            else:
                msg = LatencySamples(robot_id=robot, server_id=servers,
                                     ok=[True] * len(rtts), rtt=rtts)
            msg.header.stamp = rospy.Time.now()
            sending()
            self.pub.publish(sealed(msg, self.sealer, self.pub.resolved_name))
            return
        for server, rtt in zip(servers, rtts):
            if server == slow:
                sending()
            pub = self.pubs[(robot, server)]
            pub.publish(sealed(LatencySample(robot_id=robot, server_id=server, ok=True,
                                             rtt=rtt), self.sealer, pub.resolved_name))

    def all_ranked(self):
        with self.lock:
            return len(self.ranked) == len(self.robots)

    def trigger(self, robot):
        with self.lock:
            slow = self.flagged.get(robot)
            now = time.time()
            quiet = now - self.last_trigger.get(robot, 0.0) > QUIET and \
                now - self.changed.get(robot, 0.0) > SETTLED
            if slow is None or slow < 1 or robot in self.triggers or not quiet:
                return
            self.last_trigger[robot] = time.time()

        def sending():
            with self.lock:
                self.triggers[robot] = (time.time(), slow)
        self.send(robot, slow, sending)

    def run(self, until, rate=1.0, stop=None, out=None):
        """Probe rounds until ``until`` (epoch s) or ``stop`` (an Event) is set; the result
        written to ``out`` every 0.5 s and at the end."""
        stop = stop or threading.Event()
        period = 1.0 / (rate * len(self.robots))
        next_change = None
        index = 0
        written = 0.0
        while time.time() < until and not stop.is_set() and not rospy.is_shutdown():
            if out and time.time() - written >= 0.5:
                self.write(out)
                written = time.time()
            robot = self.robots[index % len(self.robots)]
            index += 1
            self.send(robot)
            if next_change is None and self.all_ranked():
                next_change = time.time() + 2.0
            if next_change is not None and time.time() >= next_change:
                self.trigger(self.robots[self.rng.randrange(len(self.robots))])   # if quiet
                next_change += self.change_every
            time.sleep(period)

        if out:
            self.write(out)

    def result(self):
        with self.lock:
            return {'ranked': dict(self.ranked), 'delays': list(self.delays),
                    'flags': self.flags, 'robots': len(self.robots),
                    'received': self.received[0], 'received_bytes': self.received[1]}

    def write(self, out):
        """The result so far, replacing ``out`` at once (a reader sees whole files only)."""
        with open(out + '.tmp', 'w') as stream:
            json.dump(self.result(), stream)
        os.replace(out + '.tmp', out)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--first', type=int, required=True)
    parser.add_argument('--count', type=int, required=True)
    parser.add_argument('--servers', type=int, required=True)
    parser.add_argument('--layout', choices=('robot', 'pair', 'grouped', 'view'),
                        required=True)
    parser.add_argument('--groups', type=int, default=1)
    parser.add_argument('--until', type=float, required=True, help='epoch s to stop at')
    parser.add_argument('--change-every', type=float, default=0.5)
    parser.add_argument('--rate', type=float, default=1.0, help='probe rounds per robot and s')
    parser.add_argument('--out', required=True)
    parser.add_argument('--fleet-key', help='sign the samples with this key file')
    parser.add_argument('--flag-stream', choices=('shared', 'robot'), default='shared')
    args = parser.parse_args(argv)
    rospy.init_node('scale_sim_%d' % args.first, disable_signals=True)
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    sealer = Sealer(load_keys(args.fleet_key, 'robot'), rospy.get_name()) \
        if args.fleet_key else None
    sim = SimulatedRobots(list(range(args.first, args.first + args.count)), args.servers,
                          args.layout, args.change_every, args.groups, sealer,
                          args.flag_stream)
    sim.run(args.until, args.rate, stop, args.out)
    rospy.signal_shutdown('done')


if __name__ == '__main__':
    main()
