"""Connections to this node's XML-RPC API (the master's and the peers' calls:
``publisherUpdate``, ``requestTopic``, ``getPid``) served on a bounded number of threads,
each with a deadline.

rosgraph serves every connection on a thread of its own, with no cap and no deadline: 1,000
peers that each send half an HTTP request held 1,000 threads of a node. Here at most
:data:`MOST_AT_ONCE` connections are served at once; one beyond them is closed at once
(its caller may try again), with a throttled line naming the peer. A connection has
:data:`DEADLINE` s for each request: a half-written one is closed then, and so is an idle
kept-alive one (xmlrpc.client, which the master and rospy call with, connects again by
itself).
"""

import threading

from rosgraph import xmlrpc

from server_select.core.trust.senders import Throttle
from server_select.ros.handshake import say_closed

DEADLINE = 3.0           # s a connection has for each request
MOST_AT_ONCE = 64        # connections served at once

_SLOTS = threading.BoundedSemaphore(MOST_AT_ONCE)
_THROTTLE = Throttle(5.0)
_ORIGINAL = {}


def install():
    """The bounds, from now on (before the node starts; idempotent)."""
    if _ORIGINAL:
        return
    server, handler = xmlrpc.ThreadingXMLRPCServer, xmlrpc.SilenceableXMLRPCRequestHandler
    _ORIGINAL['process_request'] = server.process_request
    _ORIGINAL['process_request_thread'] = server.process_request_thread
    _ORIGINAL['timeout'] = handler.timeout
    handler.timeout = DEADLINE
    server.process_request = _process_request
    server.process_request_thread = _process_request_thread


def _process_request(server, request, client_address):
    """The accept loop's part: the connection served on a thread, or closed."""
    if not _SLOTS.acquire(blocking=False):
        _refuse(server, request, client_address,
                'more than %d connections at once' % MOST_AT_ONCE)
        return
    try:
        _ORIGINAL['process_request'](server, request, client_address)
    except RuntimeError:           # no thread to be had: the node is stopping, or starved
        _SLOTS.release()
        _refuse(server, request, client_address, 'no thread for it')


def _process_request_thread(server, request, client_address):
    try:
        _ORIGINAL['process_request_thread'](server, request, client_address)
    finally:
        _SLOTS.release()


def _refuse(server, request, client_address, why):
    server.shutdown_request(request)
    say_closed(_THROTTLE, 'an XML-RPC connection', client_address, why)
