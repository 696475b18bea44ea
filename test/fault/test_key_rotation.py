"""The fleet's key rotated while every node serves: the operator's two commands (the new
key as every node's ``fleet_key_next``, ``reload_keys``; the two files swapped,
``reload_keys``), then the old key dropped (the new one in both files, ``reload_keys``).

No node restarts, no task fails, and tasks are answered after each step; every node
reports the same fingerprints at each step; and once the old key is dropped, what is
signed with it is refused (test/fault/spoofer.py's results, signed with the old key).
"""

import os
import subprocess
import sys
import time

from server_select.core.trust.keys import copy_key, load_keys, make_key
from server_select.core.util.procs import wait_until

from support.fleet import NODES, Fleet
from test_faults import STABLE, TASK_TIMEOUT, answered, show, warm_up

HERE = os.path.dirname(os.path.abspath(__file__))


def reload_all():
    """``rosrun server_select reload_keys``'s exit status and {node: (signs, admits)}."""
    out = subprocess.run(['rosrun', 'server_select', 'reload_keys'], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, universal_newlines=True, timeout=60)
    said = {}
    for line in out.stdout.splitlines():
        words = line.split()
        if len(words) >= 6 and words[0].endswith('/reload_keys') and words[2:4] == [
                'signs', 'with']:
            said[words[0][:-len('/reload_keys')]] = (words[4], tuple(words[6:]))
    return out.returncode, said, out.stdout


def test_keys_rotated_with_no_restart_and_no_failed_task(ros, tmp_path):
    rec = ros['rec']
    rec.clear()
    old, new = str(tmp_path / 'old.key'), str(tmp_path / 'new.key')
    make_key(old)
    make_key(new)
    prints = dict((path, load_keys(path).fingerprint()) for path in (old, new))
    sign, admit = str(tmp_path / 'sign.key'), str(tmp_path / 'admit.key')
    copy_key(old, sign)
    copy_key(old, admit)
    steps = [('stage', {admit: new}, prints[old], {prints[old], prints[new]}),
             ('swap', {sign: new, admit: old}, prints[new], {prints[old], prints[new]}),
             ('drop the old key', {admit: new}, prints[new], {prints[new]})]
    rows = []
    with Fleet(ros['log'], fleet_key=sign, fleet_key_next=admit, **STABLE) as fleet:
        warm_up(rec)
        pids = dict((node, fleet.pid(node)) for node in NODES)
        for name, files, signs, admits in steps:
            for path, source in files.items():
                copy_key(source, path)
            t_step = time.monotonic()
            status, said, out = reload_all()
            assert status == 0, out
            assert set(said) == set(NODES), out
            for node, (signed, admitted) in said.items():
                assert signed == signs, out
                assert set(admitted) == admits, out
            assert wait_until(lambda: all(answered(rec, r, t_step, 5) for r in (1, 2)), 10.0)
            rows.append({'step': name, 'nodes told': len(said),
                         'signs with': signs, 'admits': ' '.join(sorted(admits)),
                         's to 5 answered tasks': '%.2f' % (time.monotonic() - t_step)})
        subprocess.run([sys.executable, os.path.join(HERE, 'spoofer.py'), '1', '2.0',
                        'spoofer', old], stdout=subprocess.PIPE, timeout=60, check=True)
        refused = len(rec.log_lines('/robot1', 'published by /spoofer (wrong signature'))
        outcome = rec.outcomes((1, 2), TASK_TIMEOUT)
        restarted = [node for node, pid in pids.items() if fleet.pid(node) != pid]
    show('key rotated with every node serving (tasks %s):' % dict(
        (r, o['tasks']) for r, o in outcome.items()), rows + [{
            'restarted': restarted or 'none',
            'failed': sum(o['failed'] for o in outcome.values()),
            'never answered': sum(o['never answered'] for o in outcome.values()),
            "robot 1's warnings of results signed with the dropped key": refused}])
    assert not restarted
    assert all(o['failed'] == 0 and o['never answered'] == 0 for o in outcome.values()), \
        outcome
    assert refused >= 1
