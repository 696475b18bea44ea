#!/usr/bin/env python3
"""Replays recorded, sealed flags under the manager's name.

    replayer.py FILE SECONDS

registers as node ``manager`` (the master shuts the real one down) and publishes the
SelectionFlag messages serialized (hex, one a line) in FILE on ``server_select_flag``, in
turn, at 10 Hz for SECONDS s: copies of what the real manager sealed, so their seals are
right but for when they were made. Prints the number it sent.
"""

import sys
import time

import rospy

from server_select.core.config import names
from server_select.msg import SelectionFlag


def main():
    with open(sys.argv[1]) as stream:
        recorded = [bytes.fromhex(line.strip()) for line in stream if line.strip()]
    seconds = float(sys.argv[2])
    rospy.init_node('manager', disable_signals=True)
    pub = rospy.Publisher(names.SELECTION_TOPIC, SelectionFlag, queue_size=10)
    time.sleep(1.0)      # let the robots connect
    sent, end = 0, time.monotonic() + seconds
    while time.monotonic() < end:
        flag = SelectionFlag()
        flag.deserialize(recorded[sent % len(recorded)])
        pub.publish(flag)
        sent += 1
        time.sleep(0.1)
    print(sent, flush=True)


if __name__ == '__main__':
    main()
