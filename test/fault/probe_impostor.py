#!/usr/bin/env python3
"""A node that takes over servers' probe services (ROS 1 lets it: the master is no witness).

    probe_impostor.py SERVER:DELAY[,SERVER:DELAY...] SECONDS

For each server it serves ``latency_S<server>`` itself and then registers that service at
the master again under the real server's node name and API address, at its own address:
the master lists the real server as the provider, and the real server keeps running. It
answers each probe after DELAY s with the server's id, the request's seq and stamp and an
empty load, unsigned. On SIGINT (or after SECONDS) it gives every service back to its real
server (the master lists the real address again) and prints one line of JSON:
``{"answered": [[server, robot, seq, stamp ns], ...]}``.
"""

import json
import signal
import sys
import threading

import rosgraph
import rospy

from server_select.core.config import names
from server_select.srv import LatencyProbe, LatencyProbeResponse


def main():
    delays = dict((int(s), float(d)) for s, d in (p.split(':') for p in sys.argv[1].split(',')))
    seconds = float(sys.argv[2])
    done = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: done.set())
    rospy.init_node('probe_impostor', disable_signals=True)
    master = rosgraph.Master(rospy.get_name())
    lock, answered = threading.Lock(), []

    def handler(server):
        def answer(req):
            done.wait(delays[server])
            with lock:
                answered.append([server, req.robot_id, req.seq, req.stamp.to_nsec()])
            return LatencyProbeResponse(server_id=server, seq=req.seq, stamp=req.stamp,
                                        server_stamp=rospy.Time.now(), workers=1)
        return answer

    real = {}
    for server in sorted(delays):
        name = rospy.resolve_name(names.probe_service(server))
        node = '/server%d' % server
        real[server] = (name, node, master.lookupService(name), master.lookupNode(node))
        service = rospy.Service(name, LatencyProbe, handler(server))
        # under the real server's name and API: the master lists it as the provider
        rosgraph.Master(node).registerService(name, service.uri, real[server][3])
    print('serving', flush=True)
    done.wait(seconds)
    for name, node, uri, api in real.values():
        rosgraph.Master(node).registerService(name, uri, api)
    with lock:
        print(json.dumps({'answered': answered}), flush=True)


if __name__ == '__main__':
    main()
