"""The README's several-host deployment, run as an operator runs it. Every host is a network
namespace on the testbed's emulated links; each server and robot host runs its own sshd,
the manager host's operator has a key in ~/.ssh and every host in ~/.ssh/known_hosts
(ssh-keyscan). From the manager host, the README's command:

    roslaunch server_select multihost_example.launch server1_host:=... robot2_host:=...
        user:=root env_loader:=<this build>/scripts/env_loader.sh

Then one host down (its sshd gone) and the same command: what the operator sees; and the
other hosts' roles started on each host with the README's per-host commands, without it.
Needs root, TUN and sshd (Debian's openssh-server); reported skipped elsewhere, with why.
"""

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import pytest

from server_select.core.util.procs import wait_until
from server_select.testbed import netns, traces
from server_select.testbed.runner import HostRun
from server_select.testbed.scenario import Scenario

HERE = os.path.dirname(os.path.abspath(__file__))
PREFIX = traces.own_prefix('ssmh')     # this run's own namespaces
LOADER = os.path.abspath(os.path.join(HERE, '..', '..', 'scripts', 'env_loader.sh'))
WATCH = os.path.join(HERE, 'multihost_watch.py')
SSHD = shutil.which('sshd') or '/usr/sbin/sshd'
REMOTE = ('server1', 'server2', 'server3', 'robot1', 'robot2')
HOSTS = dict([('manager', {'role': 'manager'})]
             + [(h, {'role': h[:-1], 'id': int(h[-1])}) for h in REMOTE])

ok, why = netns.available()
if ok and not os.access(SSHD, os.X_OK):
    ok, why = False, 'the multi-host test needs sshd (Debian package openssh-server)'
pytestmark = pytest.mark.skipif(not ok, reason=why)

SSHD_CONFIG = """Port 22
HostKey {dir}/host_key
AuthorizedKeysFile {dir}/authorized_keys
PermitRootLogin prohibit-password
PasswordAuthentication no
KbdInteractiveAuthentication no
UsePAM no
StrictModes no
PidFile none
SetEnv ROS_HOME={dir}/remote_ros_home
"""


def keys(tmp):
    """The operator's HOME (a key in .ssh), and an sshd config that lets that key in."""
    home = tmp / 'home'
    (home / '.ssh').mkdir(parents=True, mode=0o700)
    for path in (home / '.ssh' / 'id_ed25519', tmp / 'host_key'):
        subprocess.run(['ssh-keygen', '-q', '-t', 'ed25519', '-N', '', '-f', str(path)],
                       check=True)
    shutil.copy(str(home / '.ssh' / 'id_ed25519.pub'), str(tmp / 'authorized_keys'))
    config = tmp / 'sshd_config'
    config.write_text(SSHD_CONFIG.format(dir=tmp))
    os.makedirs('/run/sshd', mode=0o755, exist_ok=True)     # sshd's privilege separation
    subprocess.run([SSHD, '-t', '-f', str(config)], check=True)
    return str(home), str(config)


def known_host(tb, env, host):
    """``ssh-keyscan -H`` of ``host`` from the manager host into known_hosts, once its sshd
    answers (as an operator does before the first roslaunch)."""
    def scan():
        out = tb.run('manager', ['ssh-keyscan', '-H', '-t', 'ed25519', tb.address(host)],
                     env=env, timeout=10).stdout
        return out if out.strip() else None
    found = wait_until(scan, 20.0, period=0.3)
    assert found, 'sshd on %s did not answer' % host
    with open(os.path.join(env['HOME'], '.ssh', 'known_hosts'), 'a') as stream:
        stream.write(scan())


def nodes_on(tb):
    """``{host: [ROS node names of the processes running in its namespace]}``."""
    found = {}
    for host, info in tb.hosts.items():
        names = []
        for pid in traces.netns_pids(info['netns']):
            try:
                with open('/proc/%d/cmdline' % pid, 'rb') as stream:
                    argv = stream.read().decode(errors='replace').split('\0')
            except OSError:        # ended meanwhile
                continue
            names += [a.split(':=', 1)[1] for a in argv if a.startswith('__name:=')]
        found[host] = sorted(names)
    return found


def watch(tb, env, tasks, timeout=90.0):
    """multihost_watch.py on the manager host: ``({robot: counts}, every robot got there)``."""
    done = tb.run('manager', [sys.executable, WATCH, '--robots', '1,2', '--tasks', str(tasks),
                              '--timeout', str(timeout)], env=env, timeout=timeout + 30)
    rows = [json.loads(line) for line in done.stdout.splitlines() if line.startswith('{')]
    robots = dict((r['robot'], r) for r in rows)
    return robots, done.returncode == 0


def operator_sees(log, *words):
    """The lines of a roslaunch log with any of ``words`` (its colours taken out)."""
    with open(log, errors='replace') as stream:
        lines = [re.sub(r'\x1b\[[0-9;]*m', '', line).rstrip() for line in stream]
    return [line for line in lines if any(w in line for w in words)]


def show(title, rows):
    print('\n' + title)
    for row in rows:
        print('  %s' % row)


def test_the_readme_several_host_commands(tmp_path):
    data = {'name': 'multihost', 'duration': 600, 'hosts': HOSTS, 'default': {'delay': 1}}
    path = str(tmp_path / 'multihost.yaml')
    with open(path, 'w') as stream:
        stream.write(json.dumps(data))                        # JSON is YAML
    home, config = keys(tmp_path)
    run_dir = str(tmp_path / 'run')
    with netns.Testbed(Scenario(data), path, run_dir, prefix=PREFIX) as tb:
        run = HostRun(tb, tb.scenario, run_dir)
        operator = dict(run.env('manager'), HOME=home)
        operator.pop('SSH_AUTH_SOCK', None)
        sshd = dict((h, tb.popen(h, [SSHD, '-D', '-e', '-f', config],
                                 log=os.path.join(run_dir, 'sshd_%s.log' % h), stage=3))
                    for h in REMOTE)
        for host in REMOTE:
            known_host(tb, operator, host)
        command = (['roslaunch', 'server_select', 'multihost_example.launch']
                   + ['%s_host:=%s' % (h, tb.address(h)) for h in REMOTE]
                   + ['user:=root', 'env_loader:=%s' % LOADER])

        # 1. every host up: the fleet runs, each node on its own host; Ctrl-C ends it all
        log = os.path.join(run_dir, 'roslaunch_all.log')
        t_launch = time.time()
        launch = tb.popen('manager', command, env=operator, log=log)
        robots, served = watch(tb, operator, tasks=5)
        where = nodes_on(tb)
        os.kill(launch.pid, signal.SIGINT)
        code = launch.wait(timeout=60)
        ended = wait_until(lambda: not any(nodes_on(tb).values()), 30.0)
        show('every host up, `roslaunch ... multihost_example.launch` from the manager host:',
             ['robot %d: flagged %.1f s after the launch, %d tasks, %d ok, %d failed, '
              'answered by %s' % (r, c['flagged'] - t_launch if c['flagged'] else -1,
                                  c['tasks'], c['ok'], c['failed'], c['answered_by'])
              for r, c in sorted(robots.items())]
             + ['nodes per host: %s' % where,
                'Ctrl-C: roslaunch exit %s, every node gone: %s' % (code, ended)])
        assert served, robots
        assert all(c['failed'] == 0 for c in robots.values()), robots
        for host in REMOTE:
            assert where[host] == [host], where               # each node on its own host
        assert 'manager' in where['manager']
        assert code == 0 and ended

        # 2. one host down: the one roslaunch for all hosts stops everything it started
        os.kill(sshd['server3'].pid, signal.SIGTERM)
        sshd['server3'].wait(timeout=10)
        log = os.path.join(run_dir, 'roslaunch_one_down.log')
        t_launch = time.monotonic()
        launch = tb.popen('manager', command, env=operator, log=log)
        code = launch.wait(timeout=90)
        t_exit = time.monotonic() - t_launch
        ended = wait_until(lambda: not any(nodes_on(tb).values()), 30.0)
        seen = operator_sees(log, tb.address('server3'), 'ERROR', 'failed')
        show('server3 down (no sshd), the same command: roslaunch exit %s after %.1f s, every '
             'node gone: %s; the operator sees:' % (code, t_exit, ended), seen)
        assert code != 0 and ended
        assert any(tb.address('server3') in line for line in seen), seen

        # 3. the README's per-host commands on the hosts that are up: the fleet runs
        run.start_master()
        per_host = [('manager', ['manager.launch', 'profile:=fleet']),
                    ('server1', ['server.launch', 'server_id:=1', 'profile:=fleet']),
                    ('server2', ['server.launch', 'server_id:=2', 'profile:=fleet']),
                    ('robot1', ['robot.launch', 'robot_id:=1', 'profile:=fleet', 'servers:=[]']),
                    ('robot2', ['robot.launch', 'robot_id:=2', 'profile:=fleet', 'servers:=[]'])]
        for host, args in per_host:
            run.popen(host, ['roslaunch', 'server_select'] + args, 'per_host_%s' % host)
        robots, served = watch(tb, run.env('manager'), tasks=5)
        show('server3 down, each other host started with its own roslaunch:',
             ['robot %d: %d tasks, %d ok, %d failed, answered by %s'
              % (r, c['tasks'], c['ok'], c['failed'], c['answered_by'])
              for r, c in sorted(robots.items())])
        assert served and all(c['failed'] == 0 for c in robots.values()), robots
        assert all(set(c['answered_by']) <= {'1', '2'} for c in robots.values()), robots
    assert traces.leftovers(PREFIX) == []
