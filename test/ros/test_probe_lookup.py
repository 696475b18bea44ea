"""A probe that must connect first asks the master where the service is within its own
deadline: a master that takes the connection and never answers (starved, stopped) fails
the lookup at the deadline instead of holding the probe's worker thread for good."""

import socket
import threading
import time
import xmlrpc.server

import pytest
import rospy

from server_select.ros.probe_client import ProbeTimeout, TimedServiceProxy, lookup_service
from server_select.srv import LatencyProbe, LatencyProbeRequest


@pytest.fixture
def master_uri(monkeypatch):
    """Point ROS_MASTER_URI at a server the test makes; yields a function that sets it."""
    def point(port):
        monkeypatch.setenv('ROS_MASTER_URI', 'http://127.0.0.1:%d' % port)
    return point


def test_a_master_that_never_answers_fails_the_lookup_at_its_deadline(master_uri):
    with socket.socket() as mute:
        mute.bind(('127.0.0.1', 0))
        mute.listen(4)                      # connections are taken; nothing is read
        master_uri(mute.getsockname()[1])
        start = time.monotonic()
        with pytest.raises(ProbeTimeout, match='/latency_S1 is within 0.3 s'):
            lookup_service('/latency_S1', 0.3)
        took = time.monotonic() - start
    print('\nlookup against a mute master gave up after %.3f s (deadline 0.3 s)' % took)
    assert 0.25 <= took < 1.0


def test_the_lookup_returns_what_the_master_lists_and_refuses_what_it_does_not(master_uri):
    listed = {'/latency_S1': 'rosrpc://127.0.0.1:4567', '/latency_S2': 'http://elsewhere:1'}

    def lookup(caller_id, name):
        return (1, 'ok', listed[name]) if name in listed else (-1, 'no provider', '')
    server = xmlrpc.server.SimpleXMLRPCServer(('127.0.0.1', 0), logRequests=False)
    server.register_function(lookup, 'lookupService')
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        master_uri(server.server_address[1])
        assert lookup_service('/latency_S1', 2.0) == 'rosrpc://127.0.0.1:4567'
        with pytest.raises(rospy.ServiceException, match='no provider'):
            lookup_service('/latency_S3', 2.0)
        with pytest.raises(rospy.ServiceException, match='latency_S2'):
            lookup_service('/latency_S2', 2.0)      # not a rosrpc URI
    finally:
        server.shutdown()
        server.server_close()


def test_a_pinned_probe_the_master_lists_no_provider_for_is_at_its_pinned_address(
        master_uri):
    """A keyed robot probes the address a server's sealed announcement names, and checks
    the answer's seal against it. After another node registered the probe service and
    left, the master lists no provider: the proxy still connects to, and names, the
    pinned address. (Before: it connected there but kept no address, and every answer
    of the server was refused as "wrong signature ... at None".)"""
    def lookup(caller_id, name):
        return -1, 'no provider', ''
    master = xmlrpc.server.SimpleXMLRPCServer(('127.0.0.1', 0), logRequests=False)
    master.register_function(lookup, 'lookupService')
    threading.Thread(target=master.serve_forever, daemon=True).start()
    with socket.socket() as server:
        server.bind(('127.0.0.1', 0))
        server.listen(4)        # connections are taken (by the kernel); nothing answers
        pinned = 'rosrpc://127.0.0.1:%d' % server.getsockname()[1]
        try:
            master_uri(master.server_address[1])
            proxy = TimedServiceProxy('/latency_S1', LatencyProbe, pinned=lambda: pinned)
            with pytest.raises(rospy.ServiceException):   # nothing answers the handshake
                proxy.call_within(LatencyProbeRequest(robot_id=1, seq=1), 0.5)
            assert proxy.uri == pinned
        finally:
            master.shutdown()
            master.server_close()
