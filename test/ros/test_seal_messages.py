"""Seals on the real message types: what a node seals, another node checks after the
message went over the wire (serialized, deserialized as the subscriber's class)."""

import io

import numpy as np
import pytest
from rospy.numpy_msg import numpy_msg

import server_select.msg
from server_select.bench.seal_cost import messages
from server_select.core.seal import Sealer, Verifier
from server_select.msg import (FleetServers, GroupAssignments, LatencySample, OrbResult,
                               SelectionFlag, ServerAnnouncement, ServerGroup, SortResult)
from server_select.ros.seal import check, sealed

KEY = b'k' * 32


def wire(msg, cls):
    """``msg`` as a subscriber of ``cls`` gets it."""
    buf = io.BytesIO()
    msg.serialize(buf)
    received = cls()
    received.deserialize(buf.getvalue())
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
    sent = sealed(msg, Sealer(KEY, '/manager'))
    assert len(sent.seal.mac) == 32
    if getattr(msg.__class__, '_has_header', False):
        sent.header.seq = 41            # as rospy's publisher numbers it, after the seal
    plain = getattr(server_select.msg, msg._type.split('/')[1])   # not the numpy view
    received = wire(sent, plain)
    assert check(received, '/manager', verifier) is None
    assert check(wire(sent, plain), '/manager', verifier).endswith('(replayed)')
    assert check(wire(sent, plain), '/impostor', verifier) == 'wrong signature'


def test_a_changed_field_or_an_unsigned_message_is_refused():
    verifier = Verifier([KEY])
    flag = sealed(SelectionFlag(robot_id=1, server_id=2, ranking=[2, 1]), Sealer(KEY, '/m'))
    changed = wire(flag, SelectionFlag)
    changed.server_id = 1
    assert check(changed, '/m', verifier) == 'wrong signature'
    assert check(SelectionFlag(robot_id=1, server_id=1), '/m', verifier) == 'not signed'
    assert check(SelectionFlag(robot_id=1, server_id=1), '/m', None) is None  # no key


def test_a_numpy_sort_result_is_checked_as_the_plain_message_it_arrives_as():
    result = numpy_msg(SortResult)(robot_id=1, task_id=1, server_id=1, ok=True,
                                   data=np.arange(1000, dtype=np.int32))
    received = wire(sealed(result, Sealer(KEY, '/server1')), SortResult)
    assert check(received, '/server1', Verifier([KEY])) is None
    received = wire(sealed(result, Sealer(KEY, '/server1')), numpy_msg(SortResult))
    assert check(received, '/server1', Verifier([KEY])) is None
