"""Ctrl-C (SIGINT) or SIGTERM while a node is still importing: kept, then acted on.

Python raises KeyboardInterrupt wherever the main thread is, and some of what a node
imports at start (message and manifest parsers) catch every exception: a node interrupted
there lost the signal and ran on until roslaunch escalated to SIGTERM and SIGKILL, 15 s
later. And rospy's own handler makes master calls on the proxy the main thread may be
using: a signal during a master call at start (``init_node``, ``get_param``) deadlocked the
node. So a node's script calls :func:`hold` first; the runner starts rospy without its
handlers, builds the node, ends it at once if :func:`held` says a signal came meanwhile,
and only then handles signals (:func:`on_signal`), while the main thread only waits.
"""

import contextlib
import signal

SIGNALS = (signal.SIGINT, signal.SIGTERM)

_HELD = []


def _keep(signum, _frame):
    _HELD.append(signum)


def hold():
    """Keep SIGINT and SIGTERM from here on (rospy's handlers, installed later, chain to
    this one and so still record them)."""
    for signum in SIGNALS:
        signal.signal(signum, _keep)


@contextlib.contextmanager
def deferred():
    """Within: SIGINT and SIGTERM are kept (:func:`held`), not handled; the handlers of
    before (rospy's) are back after."""
    before = dict((signum, signal.signal(signum, _keep)) for signum in SIGNALS)
    try:
        yield
    finally:
        for signum, handler in before.items():
            signal.signal(signum, handler)


def on_signal(callback):
    """From here on, SIGINT and SIGTERM call ``callback(signum)``."""
    for signum in SIGNALS:
        signal.signal(signum, lambda received, _frame: callback(received))


def held():
    """The signals received since :func:`hold` (empty: none)."""
    return list(_HELD)
