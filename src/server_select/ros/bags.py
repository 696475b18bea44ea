"""The one way the package reads its bags (``analyze``, ``top --bag``, the soak's history):
each message with what it is, found by the last component of its topic's name, so that a
namespaced or remapped recording reads the same as a plain one."""

import re

PAIR_SAMPLES = re.compile(r'latency_R[0-9]+S[0-9]+$')     # the paper's topic per pair
PAIR = 'latency_pair'       # what a message on one of those is


def kind_of(topic):
    """What a message on ``topic`` is: its name's last component (``task_report``,
    ``server_select_flag``, ``data``, ``rosout``...), or :data:`PAIR` for a paper sample."""
    last = topic.rsplit('/', 1)[-1]
    return PAIR if PAIR_SAMPLES.match(last) else last


def read(path, kinds=None):
    """``(kind, msg, t, sender)`` of each message of the bag at ``path`` whose kind is in
    ``kinds`` (None: every one), in the bag's order: ``t`` when it was recorded (epoch
    s), ``sender`` the node that published it."""
    import rosbag   # only here: what imports this module for kind_of needs no ROS
    with rosbag.Bag(path) as bag:
        for topic, msg, stamp, header in bag.read_messages(return_connection_header=True):
            kind = kind_of(topic)
            if kinds is not None and kind not in kinds:
                continue
            sender = header.get('callerid', b'')
            yield kind, msg, stamp.to_sec(), \
                sender.decode() if isinstance(sender, bytes) else sender
