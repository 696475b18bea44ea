"""The soak's fleet on an up testbed: every node under a name of its own, started, stopped,
signalled and restarted by name, and the master asked from inside the manager's host.

Each node runs under a ``roslaunch`` of its own in its host's namespace. A node's pid is
what the master's ``lookupNode`` and the node's XML-RPC ``getPid`` say (roslaunch starts it
in a process group of its own). Every node is given the same two key files (the key it
signs with, and one it also admits), which hold the keys of the moment: a key rotation
rewrites them and tells every node to read them again, and a node restarted later reads
them as they are. ``rosbag record`` does not register again with a restarted roscore,
so each roscore gets a recorder of its own (``soak_<n>.bag``); the analysis merges them.
"""

import os
import signal
import sys

import rosgraph

from server_select.core.trust.keys import copy_key
from server_select.core.util.procs import stop_group, stop_groups, wait_until
from server_select.ros import key_reload
from server_select.soak import plan
from server_select.testbed.master_link import CALLER, MasterLink

RECORDED = ('/(task_report|robot_rankings|fleet_servers|rosout|robot_[0-9]+/server_select_flag'
            '|server_[0-9]+/data)')
CAMERA_TOPIC = '/camera%d/image_raw/compressed' % plan.CAMERA_ROBOT
CAMERA_RATE = 1.5          # frames/s of the camera robot (about a quarter of the capacity)
BURST_RATE = 4.0           # frames/s of each burst robot: 3 of them, about 2x the capacity
TASK_RATE = 5.0            # sort tasks/s of each robot


class SoakFleet(object):
    """The nodes of a soak on ``run`` (a :class:`~server_select.testbed.runner.HostRun`);
    ``keys``: the key files of the rotations, in order (a :class:`plan.KeyRing`)."""

    def __init__(self, run, keys, frames, out):
        self.run, self.keys, self.frames, self.out = run, plan.KeyRing(keys), frames, out
        self.procs = {}             # node name: its roslaunch (or process)
        self.recorders = []
        manager = run.scenario.manager.name
        self.master = MasterLink(run.tb.hosts[manager]['netns'], run.master)
        folder = os.path.dirname(keys[0])
        self.key_files = [os.path.join(folder, name) for name in ('sign.key', 'admit.key')]
        self.install_keys()

    def install_keys(self):
        """The two key files every node is given, holding the ring's keys of the moment."""
        for path, source in zip(self.key_files, self.keys.state()):
            copy_key(source, path)

    def reload_keys(self, timeout=5.0):
        """Every node told to read its key files again: {service: its answer, or why
        none}."""
        def tell():
            master = rosgraph.Master(CALLER, master_uri=self.master.uri)
            return key_reload.call_all(key_reload.nodes_serving(master), timeout, master)
        return self.master.call(tell, timeout=60.0)

    def key_args(self):
        sign, admit = self.key_files
        return ['fleet_key:=%s' % sign, 'fleet_key_next:=%s' % admit, 'require_key:=true']

    def spec(self, name):
        """(host, launch file, arguments) of node ``name``."""
        fleet = ['profile:=fleet']
        if name == 'manager':
            return 'manager', 'manager.launch', fleet + ['robots:=[]', 'servers:=[]']
        if name.startswith('server'):
            return name, 'server.launch', fleet + ['server_id:=%s' % name[6:]]
        robot = int(name[5:])
        args = fleet + ['robot_id:=%d' % robot, 'servers:=[]', 'start_delay:=1',
                        'report_listeners:=%s' % self.recorders[-1][0]]
        if robot in plan.BURST_ROBOTS:
            host = 'robot%d' % plan.ROBOTS[plan.BURST_ROBOTS.index(robot)]
            return host, 'robot.launch', args + [
                'sort_tasks:=false', 'image_source:=%s' % self.frames,
                'frame_rate:=%g' % BURST_RATE, 'image_transport:=compressed']
        args.append('task_rate:=%g' % TASK_RATE)
        if robot == plan.CAMERA_ROBOT:
            args += ['image_topic:=%s' % CAMERA_TOPIC, 'frame_rate:=%g' % CAMERA_RATE]
        return name, 'robot.launch', args

    def start(self, name):
        host, launch, args = self.spec(name)
        self.procs[name] = self.run.launch(host, launch, *(args + self.key_args()),
                                           stage=0 if name.startswith('robot') else 1)
        return self.procs[name]

    def start_camera(self):
        host = 'robot%d' % plan.CAMERA_ROBOT
        self.procs['camera'] = self.run.popen(host, [
            sys.executable, '-m', 'server_select.bench.camera', CAMERA_TOPIC,
            str(CAMERA_RATE)], 'camera', stage=1)

    def start_intruder(self, seconds):
        """The keyless node for ``seconds``, on the first robot's host."""
        self.intruder_log = os.path.join(self.out, 'intruder.log')
        self.procs['intruder'] = proc = self.run.tb.popen(
            'robot1', [sys.executable, '-m', 'server_select.soak.intruder', str(seconds)],
            env=self.run.env('robot1'), log=self.intruder_log)
        return proc

    def intruder_said(self):
        with open(self.intruder_log) as stream:
            lines = [line for line in stream if line.startswith('{')]
        return lines[-1].strip() if lines else 'nothing (no summary line)'

    def hears(self, recorder, node):
        """Whether ``recorder`` has a connection from ``node`` (a robot: its task reports;
        any other node: its log)."""
        topic = '/task_report' if node.startswith('robot') else '/rosout'
        return any(c[1] == recorder and c[2] == 'o' and c[4] == topic
                   for c in self.master.bus_info('/' + node))

    def start_recorder(self, nodes=()):
        """A ``rosbag record`` of this roscore, as ``/soak_recorder_<n>`` into soak_<n>.bag.
        Once it hears every node of ``nodes`` (which registered again with the new master),
        the recorders of earlier roscores are stopped: each node's messages then go to one
        recorder, and its connections are the fleet's own (nothing of the soak's counts
        in its threads and descriptors)."""
        n = len(self.recorders) + 1
        name, bag = '/soak_recorder_%d' % n, os.path.join(self.out, 'soak_%d.bag' % n)
        proc = self.run.popen(self.run.scenario.manager.name, [
            'rosbag', 'record', '--tcpnodelay', '-O', bag, '-e', RECORDED,
            '__name:=%s' % name[1:]], 'recorder_%d' % n, stage=2)
        self.recorders.append((name, bag, proc))
        if not wait_until(lambda: self.pid(name) is not None, 30.0, period=0.3):
            raise RuntimeError('the recorder %s did not register within 30 s' % name)
        if nodes and wait_until(lambda: all(self.hears(name, n) for n in nodes), 60.0, 0.5):
            stop_groups([proc for _, _, proc in self.recorders[:-1] if proc.poll() is None])

    def stop(self, name, sig=signal.SIGINT):
        """Stop ``name``'s launch (SIGINT: a clean shutdown); its exit status."""
        proc = self.procs.pop(name, None)
        return stop_group(proc, sig, 15.0) if proc is not None else None

    def pid(self, name):
        return self.master.pid(name if name.startswith('/') else '/' + name)

    def signal(self, name, sig):
        """Send ``sig`` to node ``name`` (its pid from the node itself); the pid or None."""
        pid = self.pid(name)
        if pid is not None:
            os.kill(pid, sig)
        return pid

    def close(self):
        self.master.close()
