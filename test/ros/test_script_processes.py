"""The commands that start worker processes work as a user runs them (the script file,
as ``rosrun`` runs it, not ``python3 -m``): a spawned worker imports the main file again,
which must not run the command a second time. Before the scripts' ``__main__`` guard,
``rosrun server_select simulate`` ended in "Nanny failed to start"."""

import os
import subprocess
import sys

SCRIPTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'scripts')
SCENARIO = os.path.join(SCRIPTS, '..', 'config', 'sim', 'loopback.yaml')


def test_simulate_runs_its_cells_on_worker_processes(tmp_path):
    done = subprocess.run(
        [sys.executable, os.path.join(SCRIPTS, 'simulate'), SCENARIO, '--variants', 'fleet',
         '--seeds', '2', '--processes', '2', '--out', str(tmp_path)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
        timeout=300, cwd=str(tmp_path))
    assert done.returncode == 0, done.stdout[-3000:]
    assert '| fleet |' in done.stdout, done.stdout[-3000:]
    assert (tmp_path / 'league.json').exists()


def test_every_command_script_runs_only_as_the_main_file():
    """Every script that is not a node's ends in the guard (a node starts no processes)."""
    for name in sorted(os.listdir(SCRIPTS)):
        with open(os.path.join(SCRIPTS, name)) as stream:
            text = stream.read()
        if text.startswith('#!/usr/bin/env python3') and 'sys.exit(' in text:
            assert "if __name__ == '__main__':" in text, name
