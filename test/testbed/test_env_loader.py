"""The env loader of a multi-host launch gives a node the address the master's host reaches
it at: on a host with several interfaces, the source address of its route to the master,
not the first address the host lists. Run in a network namespace of its own with two
interfaces (needs root; skipped elsewhere, with why)."""

import os
import subprocess

import pytest

from server_select.testbed import netns

ok, why = netns.available()
pytestmark = pytest.mark.skipif(not ok, reason=why)

LOADER = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..', 'scripts',
                                      'env_loader.sh'))
# documentation networks (RFC 5737), inside the namespace only: "wlan" first, "eth" second
FIRST, SECOND, MASTER = '192.0.2.7/24', '198.51.100.7/24', '198.51.100.1'


def sh(*argv):
    return subprocess.run(argv, check=True, stdout=subprocess.PIPE,
                          universal_newlines=True).stdout


@pytest.fixture
def host():
    name = 'ssenv%d' % os.getpid()
    sh('ip', 'netns', 'add', name)
    try:
        run = ('ip', 'netns', 'exec', name)
        sh(*run, 'ip', 'link', 'set', 'lo', 'up')
        for index, address in enumerate((FIRST, SECOND)):
            link = 'if%d' % index                     # a veth pair, both ends inside
            sh(*run, 'ip', 'link', 'add', link, 'type', 'veth', 'peer', 'name', link + 'p')
            sh(*run, 'ip', 'addr', 'add', address, 'dev', link)
            for end in (link, link + 'p'):
                sh(*run, 'ip', 'link', 'set', end, 'up')
        yield run
    finally:
        subprocess.run(['ip', 'netns', 'del', name])


def loader_ros_ip(run, **env):
    environ = dict((k, v) for k, v in os.environ.items() if k != 'ROS_IP')
    environ.update(env)
    return subprocess.run(run + ('bash', LOADER, 'printenv', 'ROS_IP'), check=True, env=environ,
                          stdout=subprocess.PIPE, universal_newlines=True).stdout.strip()


def test_the_address_on_the_route_to_the_master_not_the_first_one(host):
    listed = sh(*host, 'hostname', '-I').split()
    chosen = loader_ros_ip(host, ROS_MASTER_URI='http://%s:11311' % MASTER)
    print('\nhost addresses %s, master %s: ROS_IP %s' % (listed, MASTER, chosen))
    assert listed[0] == FIRST.split('/')[0]            # what "the first address" would give
    assert chosen == SECOND.split('/')[0]


def test_an_explicit_ros_ip_wins_and_an_unknown_master_falls_back(host):
    assert loader_ros_ip(host, ROS_MASTER_URI='http://%s:11311' % MASTER,
                         ROS_IP='192.0.2.99') == '192.0.2.99'
    # a master name that does not resolve: the first address, as before
    assert loader_ros_ip(host, ROS_MASTER_URI='http://no-such-host.invalid:11311') == \
        FIRST.split('/')[0]
