"""Sealed flags recorded from the manager and replayed, under its name, to a robot that
restarted since (test/fault/replayer.py as ``manager``): the seals are right, the copies
are within the age limit (30 s), and the restarted robot has seen none of them; it must
refuse them all (they were signed before it started), decide alone, and say why. In the
same keyed fleet a robot started without the key says that it lacks it.
"""

import io
import os
import signal
import subprocess
import sys
import threading
import time

import rospy

from server_select.core.config import names

from server_select.core.trust import seal
from server_select.core.util.procs import wait_until
from server_select.msg import SelectionFlag

from support.fleet import Fleet
from test_faults import STABLE, answered, show, warm_up

HERE = os.path.dirname(os.path.abspath(__file__))
STEADY = dict(STABLE, policy='hysteresis')
SECONDS = 6.0      # of the replays: twice the robots' manager timeout


def test_flags_replayed_to_a_restarted_robot_count_for_nothing(ros, fleet_key, tmp_path):
    key = fleet_key
    rec, recorded, lock = ros['rec'], [], threading.Lock()
    rec.clear()

    def keep(msg):
        if msg.robot_id == 1 and msg.seal.mac:
            buf = io.BytesIO()
            msg.serialize(buf)
            with lock:
                recorded.append(buf.getvalue().hex())
    sub = rospy.Subscriber(names.SELECTION_TOPIC, SelectionFlag, keep, queue_size=100)
    try:
        with Fleet(ros['log'], fleet_key=key, **STEADY) as fleet:
            warm_up(rec)
            assert wait_until(lambda: len(recorded) >= 5, 20.0), 'no sealed flag recorded'
            sub.unregister()
            flags = tmp_path / 'flags.hex'
            with lock:
                flags.write_text('\n'.join(recorded))
            pid = fleet.signal('/robot1', signal.SIGKILL)
            assert wait_until(lambda: fleet.pid('/robot1') != pid, 10.0)
            time.sleep(seal.START_SKEW)   # what was recorded is older than that at start
            t0 = time.monotonic()
            fleet.restart_robot(1)
            assert wait_until(lambda: answered(rec, 1, t0, 5), 30.0), rec.failures(1)
            keyless = fleet.start('rosrun', 'server_select', 'robot', '_robot_id:=3',
                                  '_servers:=1,2,3', '__name:=robot3')
            out = subprocess.run([sys.executable, os.path.join(HERE, 'replayer.py'),
                                  str(flags), str(SECONDS)], stdout=subprocess.PIPE,
                                 universal_newlines=True, timeout=60, check=True)
            assert wait_until(lambda: rec.log_lines('/robot3', 'has no ~fleet_key'), 15.0)
            stop = fleet.signal('/robot3', signal.SIGINT)
            assert stop and keyless.wait(timeout=20) is not None
    finally:
        sub.unregister()
    counts = {
        'flags recorded': len(recorded), 'replayed': int(out.stdout.split()[-1]),
        "robot 1's refusals, signed before it started":
            len(rec.log_lines('/robot1', 'before this node started')),
        'robot 1 decided alone': bool(rec.log_lines('/robot1', 'from its own probes')),
        "robot 2's refusals as replayed": len(rec.log_lines('/robot2', 'replayed')),
        'keyless robot 3 warned': bool(rec.log_lines('/robot3', 'has no ~fleet_key'))}
    show('sealed flags replayed under the manager\'s name after robot 1 restarted:', [counts])
    assert counts["robot 1's refusals, signed before it started"] >= 1, counts
    assert counts['robot 1 decided alone'], counts
    assert counts['keyless robot 3 warned'], counts
