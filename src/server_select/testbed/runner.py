"""What every testbed run shares (no rospy): its options, the hosts' environments and
launches (:class:`HostRun`), the topics a run records, and the guard that turns testbed
errors and Ctrl-C into an exit status. Used by the experiment
(:mod:`~server_select.testbed.evaluation`), the scenario suite
(:mod:`~server_select.testbed.suite`) and the benchmarks on the testbed."""

import concurrent.futures
import multiprocessing
import os
import signal
import sys
import threading

from server_select.core.util.procs import wait_until
from server_select.core.settings import default
from server_select.testbed.linkemu import EmulatorError
from server_select.testbed.master_link import MasterLink
from server_select.testbed.scenario import ScenarioError

MASTER_PORT = 11311
RECORDED = ('/(latency_R[0-9]+S[0-9]+|latency_samples|fleet_servers|server_select_flag|'
            '(server_[0-9]+/)?data|(robot_[0-9]+/)?processed_data|task_report)')


class RunOptions(object):
    """What a run does besides the scenario (the nodes' defaults reproduce the paper;
    ``window``, ``probe_rate`` and ``hysteresis`` None: the profile's)."""

    def __init__(self, fixed_server=1, window=None, task_rate=default('task_rate'),
                 task_size=default('task_size'), probe_rate=None,
                 probe_timeout=default('probe_timeout'), task_timeout=default('task_timeout'),
                 start_delay=5.0, hysteresis=None, prefix=None,
                 profile=default('profile')):
        self.fixed_server = fixed_server
        self.window = window
        self.task_rate = task_rate
        self.task_size = task_size
        self.probe_rate = probe_rate
        self.probe_timeout = probe_timeout
        self.task_timeout = task_timeout
        self.start_delay = start_delay
        self.hysteresis = hysteresis
        self.prefix = prefix
        self.profile = profile


def _given(options, *names):
    """Launch arguments of the ``options`` set (None: the profile's default)."""
    return ['%s:=%g' % (n, getattr(options, n)) for n in names
            if getattr(options, n) is not None]


def node_of(launch_file, args):
    """The node a launch file of this package starts with ``args`` (``name:=`` or the
    file's default name), None for another file."""
    given = dict(a.split(':=', 1) for a in args if ':=' in a)
    base = launch_file[:-len('.launch')]
    if 'name' in given:
        return '/' + given['name']
    if base in ('server', 'robot'):
        ident = given.get(base + '_id', '-')
        return '/' + base + ('' if ident == '-' else ident)
    if base == 'manager' and given.get('group', '-') not in ('', '-'):
        return '/manager_g' + given['group']
    return '/' + base if base in ('manager', 'oracle') else None


def host_ids(hosts):
    return ','.join(str(h.id) for h in sorted(hosts, key=lambda h: h.id))


class HostRun(object):
    """One mode of one scenario on an up testbed: environments and launches per host."""

    def __init__(self, tb, scenario, run_dir):
        self.tb = tb
        self.scenario = scenario
        self.run_dir = run_dir
        self.master = 'http://%s:%d' % (tb.address(scenario.manager.name), MASTER_PORT)
        self.nodes = set()          # the nodes launched so far, by name

    def env(self, host):
        env = dict(os.environ, ROS_MASTER_URI=self.master, ROS_IP=self.tb.address(host),
                   ROS_HOME=os.path.join(self.run_dir, 'ros_home', host))
        env.pop('ROS_HOSTNAME', None)
        return env

    def popen(self, host, argv, log, stage=0):
        return self.tb.popen(host, argv, env=self.env(host),
                             log=os.path.join(self.run_dir, '%s.log' % log), stage=stage)

    def record(self, bag, *args):
        """``rosbag record ARGS`` into ``bag`` on the manager host; stopped after the nodes."""
        return self.popen(self.scenario.manager.name, ['rosbag', 'record', '--tcpnodelay',
                                                       '-O', bag] + list(args), 'rosbag', 2)

    def launch(self, host, name, *args, stage=1):
        """``roslaunch server_select NAME ARGS`` on ``host``. At the end robots (stage 0)
        stop first, then the other nodes: a robot's last task never meets a server that
        is shutting down (it would be answered busy and count as failed)."""
        node = node_of(name, args)
        if node is not None:
            self.nodes.add(node)
        return self.popen(host, ['roslaunch', '--wait', 'server_select', name] + list(args)
                          + ['output:=log'], host, stage)

    def master_link(self):
        return MasterLink(self.tb.hosts[self.scenario.manager.name]['netns'], self.master)

    def start_master(self):
        manager = self.scenario.manager.name
        self.popen(manager, ['roscore', '-p', str(MASTER_PORT)], 'roscore', stage=3)
        with self.master_link() as link:
            if not wait_until(link.up, 30.0, period=0.2):
                raise EmulatorError('roscore on %s did not come up within 30 s' % manager)

    def start_clock(self, timeout=90.0):
        """The scenario's time zero (epoch s). A scenario whose time starts once its nodes
        are up (``time_zero: ready``) starts it here, when every node launched so far is
        registered with the master."""
        if self.tb.t0 is None:
            with self.master_link() as link:
                def missing():
                    return sorted(self.nodes - link.nodes())
                if not wait_until(lambda: not missing(), timeout, period=0.2):
                    raise EmulatorError('nodes not registered within %.0f s of their launch: '
                                        '%s' % (timeout, ', '.join(missing())))
            self.tb.start_clock()
        return self.tb.t0

    def start_nodes(self, mode, options, bag):
        scenario, manager = self.scenario, self.scenario.manager.name
        servers, robots = scenario.of_role('server'), scenario.of_role('robot')
        if mode == 'select':   # fixed mode has no manager: no flag names an unused server
            fleet = options.profile == 'fleet'   # robots and servers learned at run time
            self.launch(manager, 'manager.launch', 'profile:=%s' % options.profile,
                        'robots:=%s' % ('[]' if fleet else host_ids(robots)),
                        'servers:=%s' % ('[]' if fleet else host_ids(servers)),
                        *_given(options, 'window', 'hysteresis'))
        self.record(bag, '-e', RECORDED)
        for server in servers:
            if server.start or server.stop is not None:
                threading.Thread(target=self.server_lifetime, args=(server, options),
                                 daemon=True).start()
            else:
                self.launch(server.name, 'server.launch', 'server_id:=%d' % server.id,
                            'profile:=%s' % options.profile)
        # fleet, select mode: every server found at run time (the manager lists them)
        learned = options.profile == 'fleet' and mode == 'select'
        for robot in robots:
            self.launch(robot.name, 'robot.launch', 'robot_id:=%d' % robot.id,
                        'profile:=%s' % options.profile,
                        'servers:=%s' % ('[]' if learned else host_ids(servers)),
                        'mode:=%s' % ('fixed' if mode == 'fixed' else 'select'),
                        'fixed_server:=%d' % options.fixed_server,
                        'probe_timeout:=%g' % options.probe_timeout,
                        'task_rate:=%g' % options.task_rate, 'task_size:=%d' % options.task_size,
                        'task_timeout:=%g' % options.task_timeout,
                        'start_delay:=%g' % options.start_delay,
                        'manager_node:=%s' % ('/oracle' if mode == 'oracle' else '/manager'),
                        *_given(options, 'probe_rate'), stage=0)
        if mode == 'oracle':    # told the scenario's time zero: once the others are up
            self.launch(manager, 'oracle.launch', 'scenario:=%s' % scenario.source,
                        't0:=%.6f' % self.start_clock(), 'robots:=%s' % host_ids(robots))
        self.start_clock()

    def server_lifetime(self, server, options):
        """A server that starts late or stops early (the scenario's ``start`` / ``stop``):
        launched at its start, stopped with SIGINT (a clean shutdown) at its stop."""
        self.tb.sleep_until(server.start)
        proc = self.launch(server.name, 'server.launch', 'server_id:=%d' % server.id,
                           'profile:=%s' % options.profile)
        if server.stop is not None:
            self.tb.sleep_until(server.stop)
            proc.send_signal(signal.SIGINT)


def at_once(calls):
    """Run each ``(function, args)`` of ``calls`` at once, each in a process of its own (a
    fresh interpreter, whose main thread a :class:`Testbed` may set signal handlers in);
    their results in order (an exception of one is raised here)."""
    context = multiprocessing.get_context('spawn')
    with concurrent.futures.ProcessPoolExecutor(len(calls), mp_context=context) as pool:
        futures = [pool.submit(function, *args) for function, args in calls]
        return [future.result() for future in futures]


def guarded(prog, work):
    """Run ``work()``; 0, or 2 (a testbed or scenario error, said on stderr) or 130
    (interrupted; the testbed was torn down on the way out)."""
    try:
        work()
    except (EmulatorError, ScenarioError) as error:
        print('%s: %s' % (prog, error), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print('%s: interrupted; the testbed was torn down' % prog, file=sys.stderr)
        return 130
    return 0
