"""The manager's inputs (its wiring stays in :mod:`server_select.nodes.manager`): samples
per pair, robots' probe batches, their answered tasks, their own rankings; each checked
(who published it, what it claims, its values) before the rankings take it."""

import rospy

from server_select.core.config import names
from server_select.core.ranking.rank import from_view
from server_select.core.ranking.window import RTT_RANGE, valid_rtt
from server_select.ros.graph import publisher_of


class SampleIntake(object):
    """What the manager hears, into ``rankings`` (SampleRankings or ViewRankings); refused
    input gets a throttled warning naming its publisher. ``senders``: the gate of robots'
    messages; ``group``: a group's manager ignores the other groups' robots;
    ``update(robot)``: the robot's ranking may have changed."""

    def __init__(self, rankings, senders, group, update):
        self.rankings, self.senders, self.group = rankings, senders, group
        self.update = update

    def on_sample(self, sample, pair):
        """One sample on the topic of ``pair`` (paper layout)."""
        if not self.senders.admits(sample, lambda: 'a sample on %s' % names.sample_topic(*pair),
                                   pair[0]):
            return
        why = self.refuse(sample, pair[0], pair)
        if why:
            self.warn(names.sample_topic(*pair), sample, why)
        else:
            self.take(pair[0], pair[1], sample.ok, sample.rtt, rospy.get_time())

    def on_view(self, msg):
        """A robot's own ranking (``~sample_stream view``)."""
        robot = msg.robot_id
        if self.group is not None and self.rankings.robot_refusal(robot):
            return      # a robot of another group
        if not self.senders.admits(msg, lambda: 'a ranking on %s' % names.RANKINGS_TOPIC,
                                   robot):
            return
        why = self.refuse(msg, robot)
        try:
            ranking = from_view(msg.ranking, msg.mean_latency, msg.error, msg.sample_count,
                                msg.wait, msg.excluded, msg.selected, msg.reason) \
                if why is None else None
        except ValueError as error:
            why = str(error)
        if why:
            self.warn(names.RANKINGS_TOPIC, msg, why)
            return
        self.rankings.take(robot, rospy.get_time(), ranking)
        self.update(robot)

    def on_batch(self, batch, topic=names.SAMPLES_TOPIC):
        """One robot's probe round (fleet layout), or its answered tasks (``~passive``)."""
        robot = batch.robot_id
        if self.group is not None and self.rankings.robot_refusal(robot):
            return      # a robot of another group: not ours to rank
        count = len(batch.server_id)
        if not self.senders.admits(batch, lambda: 'samples on %s' % topic, robot):
            return
        why = self.refuse(batch, robot)
        waits = batch.wait or [0.0] * count     # load-aware robots: rank by rtt + wait
        if why is None and not len(batch.ok) == len(batch.rtt) == len(waits) == count:
            why = 'arrays of %d servers, %d ok, %d rtt, %d wait' % (
                count, len(batch.ok), len(batch.rtt), len(batch.wait))
        if why:
            self.warn(topic, batch, why)
            return
        now = rospy.get_time()
        changed = False
        for server, ok, rtt, wait in zip(batch.server_id, batch.ok, batch.rtt, waits):
            why = self.rankings.refusal(robot, server)
            if why is not None and self.group is not None:
                continue    # another group's representative: probed for the top manager
            if why is None and ok and not (valid_rtt(rtt) and valid_rtt(wait)):
                why = 'round trip %r + wait %r of server %d is not %s' % (
                    rtt, wait, server, RTT_RANGE)
            if why:
                self.warn(topic, batch, why)
                continue
            if self.rankings.add(robot, server, now, ok, rtt + wait,
                                 probe=topic != names.TASK_SAMPLES_TOPIC,
                                 wait=wait if batch.wait else None):
                changed = True
        if changed:     # one ranking per batch: O(1) per sample
            self.update(robot)

    def take(self, robot, server, ok, rtt, now):
        if self.rankings.add(robot, server, now, ok, rtt):
            self.update(robot)

    def refuse(self, msg, robot, pair=None):
        """Why ``msg`` (a sample, or a batch when ``pair`` is None) must be ignored."""
        if pair is not None and (msg.robot_id, msg.server_id) != pair:
            return 'it claims robot %d / server %d' % (msg.robot_id, msg.server_id)
        if pair is not None and msg.ok and not valid_rtt(msg.rtt):
            return 'round trip %r is not %s' % (msg.rtt, RTT_RANGE)
        if pair is None and self.rankings.robot_refusal(robot):
            return self.rankings.robot_refusal(robot)
        return None

    def warn(self, topic, msg, why):
        rospy.logwarn_throttle(5.0, 'manager: ignored a sample on %s published by %s: %s'
                               % (topic, publisher_of(msg), why))
