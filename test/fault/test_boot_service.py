"""Hosts that start themselves: the units ``install_service`` writes, run as systemd would
run them (their command line, their environment and nothing else), on a master of their own.

The server host boots before the master host: its role waits for the master and comes up
when the master does; ``systemctl stop`` (SIGINT to every process of the unit) ends the role
cleanly. Restarting a unit that ended (``Restart=always``) is systemd's part and is not run
here; ``systemd-analyze verify`` checks the units where it exists.
"""

import os
import shutil
import signal
import subprocess
import sys
import time
import xmlrpc.client

import psutil
import pytest

from server_select.bench.harness import free_port
from server_select.core.util.procs import wait_until
from server_select.service_unit import main, parse_unit

HERE = os.path.dirname(os.path.abspath(__file__))
LOADER = os.path.abspath(os.path.join(HERE, '..', '..', 'scripts', 'env_loader.sh'))
# what systemd gives a service besides its Environment= lines
SYSTEMD_PATH = '/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin'


def install(tmp_path, *argv):
    out = tmp_path / 'units'
    out.mkdir(exist_ok=True)
    before = set(os.listdir(str(out)))
    assert main(list(argv) + ['--loader', LOADER, '--unit-dir', str(out),
                              '--ros-ip', '127.0.0.1', '--ros-home', str(tmp_path)]) == 0
    (name,) = set(os.listdir(str(out))) - before
    return out / name


def start(unit, log):
    """Run ``unit`` as systemd would: its command, its environment only."""
    env, cmd, _ = parse_unit(unit.read_text())
    env = dict(env, PATH=SYSTEMD_PATH, HOME=str(log.parent), LANG='C.UTF-8')
    with open(str(log), 'a') as stream:
        return subprocess.Popen(cmd, env=env, stdout=stream, stderr=subprocess.STDOUT,
                                start_new_session=True)


def stop(proc, timeout=20.0):
    """``systemctl stop``: SIGINT to every process of the unit, then wait for them all
    (TimeoutStopSec); returns those still running."""
    procs = [psutil.Process(proc.pid)] + psutil.Process(proc.pid).children(recursive=True)
    for p in procs:
        try:
            p.send_signal(signal.SIGINT)
        except psutil.NoSuchProcess:
            pass
    _, alive = psutil.wait_procs(procs, timeout=timeout)
    for p in alive:
        p.kill()
    proc.wait()
    return alive


def served(uri, service):
    try:
        code, _, _ = xmlrpc.client.ServerProxy(uri).lookupService('/boot_test', service)
        return code == 1
    except OSError:
        return False


def test_a_server_host_that_boots_before_the_master_comes_up_with_it(tmp_path):
    master = 'http://127.0.0.1:%d' % free_port()
    server = install(tmp_path, 'server', 'server_id:=7', 'profile:=fleet', '--master', master)
    core = install(tmp_path, 'roscore', '--master', master)
    log = tmp_path / 'units.log'
    role = start(server, log)
    master_proc = None
    try:
        # the role waits for a master that is not there yet
        assert wait_until(lambda: 'will wait for it to start' in log.read_text() or
                          role.poll() is not None, 30.0), log.read_text()[-2000:]
        assert role.poll() is None, log.read_text()[-2000:]
        master_proc = start(core, log)
        t_master = time.monotonic()
        assert wait_until(lambda: served(master, '/latency_S7'), 60.0), log.read_text()[-3000:]
        up = time.monotonic() - t_master
        env = dict(os.environ, ROS_MASTER_URI=master, ROS_IP='127.0.0.1')
        answer = subprocess.run(['rosservice', 'call', '/latency_S7', '{robot_id: 99, seq: 7}'],
                                env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                universal_newlines=True, timeout=60)
        assert 'server_id: 7' in answer.stdout and 'seq: 7' in answer.stdout, answer.stdout
        left = stop(role)
        print('\nserver unit started before the master: its probe service served %.1f s after '
              'the master unit started; systemctl stop left %d processes' % (up, len(left)))
        assert left == [] and role.returncode == 0, (left, role.returncode)
        assert 'server 7' in log.read_text()
    finally:
        for proc in (role, master_proc):
            if proc is not None and proc.poll() is None:
                stop(proc)


@pytest.mark.skipif(shutil.which('systemd-analyze') is None,
                    reason='systemd-analyze is not installed')
def test_systemd_accepts_the_units(tmp_path):
    units = [install(tmp_path, 'robot', 'robot_id:=3', 'profile:=fleet', 'servers:=[]',
                     '--master', 'http://10.0.0.1:11311'),
             install(tmp_path, 'roscore', '--master', 'http://10.0.0.1:11311')]
    check = subprocess.run(['systemd-analyze', 'verify'] + [str(u) for u in units],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           universal_newlines=True, timeout=60)
    problems = [line for line in check.stdout.splitlines()
                if any(str(u) in line for u in units)]
    assert problems == [], check.stdout
    if check.returncode != 0:     # it named none of the units: it could not run here
        pytest.skip('systemd-analyze verify could not check the units here (exit %d): %s'
                    % (check.returncode, check.stdout.strip()[-300:]))
    print('\nsystemd-analyze verify: %s' % (check.stdout.strip() or 'no remarks'))


if __name__ == '__main__':
    sys.exit(pytest.main([__file__, '-s']))
