"""Seals on the real message types: what a node seals, another node checks after the
message went over the wire (serialized, deserialized as the subscriber's class)."""

import io

import numpy as np
import pytest
from rospy.numpy_msg import numpy_msg

import server_select.msg
from server_select.bench.seal_cost import messages
from server_select.core.trust.seal import Keys, Sealer, Verifier, publisher_role
from server_select.msg import (FleetServers, GroupAssignments, LatencySample, OrbResult,
                               SelectionFlag, ServerAnnouncement, ServerGroup, SortResult)
from server_select.ros.seal import check, sealed

SECRET = b'k' * 32
KEY = Keys.from_fleet(SECRET, 'server')          # what a server signs with
TOPIC = '/robot_1/processed_data'


def wire(msg, cls):
    """``msg`` as a subscriber of ``cls`` gets it."""
    buf = io.BytesIO()
    msg.serialize(buf)
    received = cls()
    received.deserialize(buf.getvalue())
    received._connection_header = {'topic': TOPIC, 'callerid': '/x'}
    return received


def every_message():
    made = [make() for _, make in messages()]
    made += [LatencySample(robot_id=1, server_id=2, ok=True, rtt=1e-3),
             FleetServers(servers=[1, 2, 3]), ServerAnnouncement(server_id=2, lease=6.0),
             GroupAssignments(groups=[ServerGroup(group_id=1, servers=[1, 2])], robot_id=[1],
                              group_id=[1]),
             OrbResult(robot_id=1, task_id=2, server_id=3, ok=True)]
    return made


@pytest.mark.parametrize('msg', every_message(), ids=lambda m: m._type)
def test_a_message_sealed_by_one_node_is_admitted_by_another_after_the_wire(msg):
    verifier = Verifier([KEY])
    sent = sealed(msg, Sealer(Keys.from_fleet(SECRET, publisher_role(msg._type)), '/manager'),
                  TOPIC)
    assert len(sent.seal.mac) == 64
    if getattr(msg.__class__, '_has_header', False):
        sent.header.seq = 41            # as rospy's publisher numbers it, after the seal
    plain = getattr(server_select.msg, msg._type.split('/')[1])   # not the numpy view
    received = wire(sent, plain)
    assert check(received, '/manager', verifier) is None
    assert check(wire(sent, plain), '/manager', verifier).endswith('(replayed)')
    assert check(wire(sent, plain), '/impostor', verifier).startswith('wrong signature')
    assert check(wire(sent, plain), '/manager', verifier, TOPIC).endswith('(replayed)')
    assert check(wire(sent, plain), '/manager', verifier, '/other').startswith('wrong')
    unknown = wire(sent, plain)
    del unknown._connection_header
    assert check(unknown, '/manager', verifier) == 'no topic known to check its seal against'


def test_a_changed_field_or_an_unsigned_message_is_refused():
    verifier = Verifier([KEY])
    flag = sealed(SelectionFlag(robot_id=1, server_id=2, ranking=[2, 1]),
                  Sealer(Keys.from_fleet(SECRET, 'manager'), '/m'), TOPIC)
    changed = wire(flag, SelectionFlag)
    changed.server_id = 1
    assert check(changed, '/m', verifier).startswith('wrong signature')
    assert check(SelectionFlag(robot_id=1, server_id=1), '/m', verifier) == 'not signed'
    assert check(SelectionFlag(robot_id=1, server_id=1), '/m', None) is None  # no key


def test_a_numpy_sort_result_is_checked_as_the_plain_message_it_arrives_as():
    result = numpy_msg(SortResult)(robot_id=1, task_id=1, server_id=1, ok=True,
                                   data=np.arange(1000, dtype=np.int32))
    received = wire(sealed(result, Sealer(KEY, '/server1'), TOPIC), SortResult)
    assert check(received, '/server1', Verifier([KEY])) is None
    received = wire(sealed(result, Sealer(KEY, '/server1'), TOPIC), numpy_msg(SortResult))
    assert check(received, '/server1', Verifier([KEY])) is None


def test_a_probe_answer_counts_for_its_own_request_server_and_address_only():
    from server_select.ros.seal import _answer_channel
    from server_select.srv import LatencyProbeRequest, LatencyProbeResponse
    service, uri = '/latency_S1', 'rosrpc://server1:40001'
    request = LatencyProbeRequest(robot_id=1, seq=7, nonce=123456789)
    answer = sealed(LatencyProbeResponse(server_id=1, seq=7, workers=1),
                    Sealer(KEY, '/server1'), _answer_channel(service, uri, request))

    def refusal(server_node='/server1', at=uri, req=request, msg=answer):
        return check(wire(msg, LatencyProbeResponse), server_node, Verifier([KEY]),
                     _answer_channel(service, at, req))
    assert refusal() is None
    other = LatencyProbeRequest(robot_id=1, seq=7, nonce=987654321)    # another probe
    assert refusal(req=other).startswith('wrong signature')
    assert refusal(at='rosrpc://impostor:40002').startswith('wrong signature')   # relayed
    assert refusal(server_node='/impostor').startswith('wrong signature')
    assert refusal(msg=LatencyProbeResponse(server_id=1, seq=7)) == 'not signed'


def test_one_flag_sealed_for_two_topics_keeps_each_topics_seal():
    """The manager publishes one flag on the robot's latched topic, then on the shared one:
    the latched publisher keeps the object, so sealing for the second topic must not
    change what the first holds."""
    sealer = Sealer(Keys.from_fleet(SECRET, 'manager'), '/manager')
    flag = SelectionFlag(robot_id=1, server_id=2, ranking=[2, 1])
    own = sealed(flag, sealer, '/robot_1/server_select_flag')
    sealed(flag, sealer, '/server_select_flag')
    received = wire(own, SelectionFlag)
    received._connection_header['topic'] = '/robot_1/server_select_flag'
    assert check(received, '/manager', Verifier([KEY])) is None
