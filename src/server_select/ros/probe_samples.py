"""Where a robot's probe samples go: one topic per pair (the paper) or a batch per round."""

import rospy

from server_select.core.config import names
from server_select.msg import LatencySample, LatencySamples
from server_select.ros.node import fleet, unregister
from server_select.ros.seal import SealedPublisher


class ProbeSamples(object):
    """``stream`` ``pair`` publishes each sample on ``latency_R<r>S<s>`` (the paper);
    ``robot`` and ``view`` one ``latency_samples`` batch per round (a ``ProbeRound``),
    when its last probe has ended; ``waits``: the batch carries each answer's wait."""

    def __init__(self, robot_id, stream, waits):
        self.robot_id, self.stream, self.waits = robot_id, stream, waits
        self._pubs = {}
        self._batch_pub = SealedPublisher(fleet(names.SAMPLES_TOPIC), LatencySamples,
                                          queue_size=10) if stream != 'pair' else None

    @property
    def batched(self):
        return self._batch_pub is not None

    def add(self, server):
        if self.stream == 'pair' and server not in self._pubs:
            self._pubs[server] = SealedPublisher(
                fleet(names.sample_topic(self.robot_id, server)), LatencySample, queue_size=10)

    def remove(self, server):
        pub = self._pubs.pop(server, None)
        if pub is not None:
            unregister(pub)

    def sample(self, server, seq, stamp, rtt, error):
        """One sample (``rtt`` None: failed, for ``error``)."""
        if error:
            rospy.logdebug('robot %d: probe of server %d failed: %s', self.robot_id, server, error)
        pub = self._pubs.get(server)
        if pub is not None:
            sample = LatencySample(robot_id=self.robot_id, server_id=server, seq=seq,
                                   ok=rtt is not None, rtt=rtt or 0.0, error=error)
            sample.header.stamp = stamp
            pub.publish(sample)

    def round(self, batch):
        """A round whose last probe has ended."""
        servers, oks, rtts, waits = zip(*sorted(batch.samples)) if batch.samples \
            else ((), (), (), ())
        msg = LatencySamples(robot_id=self.robot_id, round=batch.number, server_id=servers,
                             ok=oks, rtt=rtts, wait=waits if self.waits else ())
        msg.header.stamp = batch.stamp
        self._batch_pub.publish(msg)
