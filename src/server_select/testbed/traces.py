"""What testbed runs leave behind, and whose it is (no rospy): each run's namespaces
``<prefix>-<host>``, the processes inside them, its emulator, its CPU groups and a state
file in ``/run`` naming its owner process. A run removes only what its prefix names, and
what a run whose owner has died left behind; tests and benchmarks name their runs with
:func:`own_prefix`, so that two runs on one machine leave each other alone.
"""

import json
import os
import subprocess

from server_select.core.util.procs import alive, kill_all
from server_select.testbed import cpu

STATE_DIR = '/run/server_select-testbed'


def own_prefix(tag):
    """``tag`` (its first 5 characters) and this process's id in 5 digits: a prefix no other
    run on this machine has, nor begins another's (a device is the prefix and a number: 15
    characters at most)."""
    return '%s%05d' % (tag[:5], os.getpid() % 100000)


def _netns_list():
    out = subprocess.run(['ip', 'netns', 'list'], stdout=subprocess.PIPE,
                         universal_newlines=True, check=False).stdout
    return [line.split()[0] for line in out.splitlines() if line.strip()]


def netns_pids(netns):
    out = subprocess.run(['ip', 'netns', 'pids', netns], stdout=subprocess.PIPE,
                         stderr=subprocess.DEVNULL, universal_newlines=True, check=False).stdout
    return [int(p) for p in out.split()]


def cleanup(prefix):
    """Remove the namespaces, processes and emulator a run with ``prefix`` left behind."""
    removed = []
    state = os.path.join(STATE_DIR, prefix + '.json')
    if os.path.exists(state):
        try:
            with open(state) as stream:
                pid = json.load(stream).get('emulator_pid')
            if pid and alive(pid):
                kill_all([pid])
                removed.append('emulator %d' % pid)
        except (OSError, ValueError):
            pass
        os.unlink(state)
    for netns in _netns_list():
        if netns.startswith(prefix + '-'):
            kill_all(netns_pids(netns))
            subprocess.run(['ip', 'netns', 'del', netns], check=False)
            removed.append(netns)
    return removed + cpu.cleanup(prefix)


def cleanup_abandoned():
    """Clean up after every run whose owner process is gone; returns what was removed."""
    removed = []
    try:
        states = [f for f in os.listdir(STATE_DIR) if f.endswith('.json')]
    except OSError:
        return removed
    for name in states:
        try:
            with open(os.path.join(STATE_DIR, name)) as stream:
                owner = json.load(stream).get('owner_pid')
        except (OSError, ValueError):
            continue
        if owner and owner != os.getpid() and not alive(owner):
            removed += cleanup(name[:-len('.json')])
    return removed


def leftovers(prefix):
    """What of a testbed with ``prefix`` still exists (for tests of the teardown)."""
    found = [n for n in _netns_list() if n.startswith(prefix + '-')]
    links = subprocess.run(['ip', '-o', 'link'], stdout=subprocess.PIPE,
                           universal_newlines=True, check=False).stdout
    found += [x.split(':')[1].strip() for x in links.splitlines()
              if x.split(':')[1].strip().startswith(prefix)] + cpu.leftovers(prefix)
    try:
        found += ['state file %s' % f for f in os.listdir(STATE_DIR)
                  if f.startswith(prefix) and f.endswith('.json')]
    except OSError:
        pass
    return found
