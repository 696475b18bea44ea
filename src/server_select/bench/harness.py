"""What the benchmarks run on: a roscore of their own, a small fleet, the task reports."""

import contextlib
import json
import os
import random
import socket
import subprocess
import sys
import threading
import time
import xmlrpc.client

from server_select.core.config import names
from server_select.core.flow.outcome import cut_off
from server_select.core.util.procs import kill_all, stop_group, wait_until
from server_select.ros.graph import node_pid as graph_node_pid

PY = [sys.executable, '-m']


def _ephemeral_ports():
    """The kernel's range for ports it picks itself (outgoing connections, bind to 0)."""
    try:
        with open('/proc/sys/net/ipv4/ip_local_port_range') as f:
            low, high = (int(x) for x in f.read().split())
        return low, high
    except (OSError, ValueError):
        return 32768, 60999


def free_port():
    """A port free now and below the kernel's ephemeral range: a port the kernel picked
    (bind to 0) and closed again could be taken by any process's next outgoing connection
    before roscore binds it, or while a killed roscore's successor waits to bind it again
    (nodes keep connecting to the master that went away)."""
    low = _ephemeral_ports()[0]
    ports = range(20000, low) if low > 21000 else range(1024, low)
    for _ in range(100):
        port = random.choice(ports)
        if port == 11311:       # a user's own roscore
            continue
        with contextlib.closing(socket.socket()) as s:
            try:
                s.bind(('127.0.0.1', port))
            except OSError:
                continue
        return port
    raise RuntimeError('no free port below %d' % low)


def master_up(uri):
    """Whether the master at ``uri`` answers (a roscore started, or started again)."""
    try:
        xmlrpc.client.ServerProxy(uri).getPid('/bench')
        return True
    except OSError:
        return False


class Roscore(object):
    """A roscore on a free port, its URI exported to this process and its children."""

    def __init__(self, log_dir):
        self.port = free_port()
        self.uri = 'http://127.0.0.1:%d' % self.port
        self.log_dir = log_dir
        self.proc = None

    def __enter__(self):
        os.environ.setdefault('ROS_HOME', self.log_dir)
        for _ in range(3):      # another process may bind the port first: another port
            os.environ['ROS_MASTER_URI'] = self.uri
            self.proc = subprocess.Popen(['roscore', '-p', str(self.port)],
                                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                         start_new_session=True)
            if wait_until(lambda: master_up(self.uri) or self.proc.poll() is not None,
                          30.0, period=0.2) and self.proc.poll() is None:
                return self
            stop_group(self.proc)
            self.port = free_port()
            self.uri = 'http://127.0.0.1:%d' % self.port
        raise RuntimeError('roscore did not start (last on port %d)' % self.port)

    def __exit__(self, *exc):
        # roslaunch starts rosout in a process group of its own: stopping roscore's group
        # left it running (one rosout a fault-test run); its pid from its own XML-RPC API
        rosout = pid_or_none('/rosout', self.uri)
        stop_group(self.proc)
        if rosout is not None:
            kill_all([rosout])
        return False


def node_pid(name):
    return graph_node_pid(name, '/bench')


def pid_or_none(name, master_uri=None):
    """The pid of node ``name`` at the master (``master_uri``: another than this process's),
    or None while it is not registered or does not answer."""
    import rosgraph
    try:
        return graph_node_pid(name, '/bench', master=rosgraph.Master(
            '/bench', master_uri=master_uri) if master_uri else None)
    except Exception:   # not registered (yet), gone, or the master is busy
        return None


def pids_of(nodes, master=None):
    """``{node: pid}`` of ``nodes`` at ``master`` (None: this process's), or None while any
    of them is not registered or does not answer (asked in order, up to the first missing:
    a fleet coming up is polled with a master call or two, not two a node)."""
    pids = {}
    for node in nodes:
        pids[node] = pid_or_none(node, master)
        if pids[node] is None:
            return None
    return pids


@contextlib.contextmanager
def launched(launch, args, log, master=None, nodes=(), timeout=60.0, env=None):
    """The benchmarks' fleet of real nodes: ``roslaunch`` of ``launch`` (a file in the
    package, or a path) with ``args`` (``name:=value``) under ``master`` (None: this
    process's), in a session of its own with ``env`` added to the environment, its output
    appended to the file ``log``. Yields
    ``{node: pid}`` once every one of ``nodes`` is registered (RuntimeError naming the log
    after ``timeout`` s, or if roslaunch ends first); on leaving, stops its process group
    and kills any of ``nodes`` still registered (roslaunch starts each node in a group of
    its own, and a loaded host may outlast its shutdown timeout: the next fleet's nodes
    take these names)."""
    env = dict(os.environ, **dict(env or {}, **({'ROS_MASTER_URI': master} if master else {})))
    where = [launch] if os.path.isabs(launch) else ['server_select', launch]
    with open(log, 'a') as stream:
        proc = subprocess.Popen(['roslaunch'] + where + list(args), stdout=stream,
                                stderr=subprocess.STDOUT, env=env, start_new_session=True)
    try:
        up = wait_until(lambda: proc.poll() is not None or pids_of(nodes, master) is not None,
                        timeout, period=0.3)
        pids = pids_of(nodes, master)
        if not up or proc.poll() is not None or pids is None:
            raise RuntimeError('%s did not bring up %s in %g s (see %s)'
                               % (launch, ', '.join(nodes), timeout, log))
        yield pids
    finally:
        stop_group(proc, timeout=20.0)
        kill_all([p for p in (pid_or_none(n, master) for n in nodes) if p is not None])


def fleet(log, **args):
    """bench_fleet.launch with ``args``; yields once robot1 and server1 are registered."""
    return launched('bench_fleet.launch', ['%s:=%s' % kv for kv in sorted(args.items())],
                    log, nodes=('/robot1', '/server1'), timeout=40.0)


class ReportListener(object):
    """task_report messages received by this process (the benchmark driver)."""

    def __init__(self):
        import rospy
        from server_select.msg import TaskReport
        self.lock = threading.Lock()
        self.reports = []
        self.sub = rospy.Subscriber(names.TASK_REPORT_TOPIC, TaskReport, self.on_report,
                                    queue_size=10000)

    def on_report(self, msg):
        if cut_off(msg.error):      # a robot stopped with it out: the run's end, not a result
            return
        with self.lock:
            self.reports.append((time.monotonic(), msg))

    def wait_for_answer(self, kind, timeout=40.0):
        """Wait until a task of ``kind`` is answered (ok) after this call: the fleet has
        selected, and the server has loaded what its work needs. False after ``timeout``."""
        since = time.monotonic()

        def answered():
            with self.lock:
                for t, m in reversed(self.reports):
                    if t < since:
                        return False
                    if m.kind == kind and m.ok:
                        return True
            return False
        return wait_until(answered, timeout, period=0.05)

    def between(self, start, end, kind):
        with self.lock:
            return [m for t, m in self.reports if start <= t < end and m.kind == kind]


def us(summary):
    return dict((k, v * 1e6 if k != 'n' else v) for k, v in summary.items())


@contextlib.contextmanager
def scenario_run(data, work, name, prefix, record=('/task_report',)):
    """The scenario ``data`` (a dict) up on the testbed under ``work/name`` with its
    roscore and a rosbag recording ``record``: yields ``(HostRun, bag path)``; the run
    lasts until the scenario's duration once the block has started the nodes (whose
    registration starts a ``time_zero: ready`` scenario's time). The link
    emulator's counts are then in ``work/name/link_stats.json``, and the scenario's time
    zero beside the bag (``<bag>.json``), so that a loaded bag's times are scenario times.
    ``prefix``: the tag of the run's namespaces (``traces.own_prefix``)."""
    import yaml
    from server_select.testbed.runner import HostRun
    from server_select.testbed.netns import Testbed
    from server_select.testbed.traces import own_prefix
    from server_select.testbed.scenario import Scenario
    path = os.path.join(work, name + '.yaml')
    with open(path, 'w') as stream:
        yaml.safe_dump(data, stream)
    run_dir, bag = os.path.join(work, name), os.path.join(work, name + '.bag')
    with Testbed(Scenario(data), path, run_dir, prefix=own_prefix(prefix)) as tb:
        run = HostRun(tb, tb.scenario, run_dir)
        run.start_master()
        run.record(bag, *record)
        yield run, bag
        run.start_clock()
        tb.sleep_until(tb.scenario.duration)
    with open(bag + '.json', 'w') as stream:
        json.dump({'t0': tb.t0}, stream)


def link_bytes(work, name):
    """The link emulator's per-direction counts of the run ``work/name``."""
    with open(os.path.join(work, name, 'link_stats.json')) as stream:
        return json.load(stream)
