"""The simulated league, the simulate command and the calibration in tiny configurations
(seconds): each writes its tables, JSON and plot, with a cell for every run asked for."""

import json
import subprocess
import sys


def run(*args):
    proc = subprocess.run([sys.executable, '-m'] + list(args), stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, universal_newlines=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
    return proc.stdout


def test_the_simulated_league_writes_every_cell(tmp_path):
    out = run('server_select.sim.league', '--seeds', '2', '--scenarios', 'near_equal,gen:3',
              '--variants', 'oracle_fleet,fleet,prequal', '--cases', 'herd',
              '--capacity-variants', 'static,fleet', '--processes', '1',
              '--out', str(tmp_path))
    results = json.loads((tmp_path / 'league.json').read_text())
    for name in ('near_equal', 'gen:3'):
        assert sorted(results['network'][name]) == ['fleet', 'oracle_fleet', 'prequal']
        assert all(sorted(runs) == ['1', '2'] for runs in results['network'][name].values())
    assert sorted(results['capacity']['herd']) == ['fleet', 'static']
    assert 'fleet - prequal' in out and '### herd (capacity)' in out
    assert (tmp_path / 'league.png').stat().st_size > 1000


def test_the_simulate_command_takes_a_scenario_file(tmp_path):
    run('server_select.sim.generate', '--first-seed', '9', '--count', '1',
        '--out', str(tmp_path))
    out = run('server_select.sim.cli', str(tmp_path / 'gen9.yaml'), '--variants',
              'fleet,round_robin', '--seeds', '2', '--processes', '1',
              '--out', str(tmp_path / 'out'))
    assert '| round_robin |' in out and 'fleet - round_robin' in out


def test_the_calibration_compares_every_cell_of_a_part():
    out = run('server_select.sim.calibration', '--part', 'capacity', '--seeds', '1',
              '--processes', '1')
    assert out.count('| herd') == 8 and 'cells within 10 %' in out


def test_a_calibration_cell_is_close_within_10_percent_or_inside_the_testbeds_range():
    from server_select.sim.calibration import close
    assert close(1.09, 1.0, 0.9, 1.05) and close(1.3, 1.0, 0.8, 1.4)
    assert not close(1.2, 1.0, 0.9, 1.1) and not close(0.5, 0.0, 0.0, 0.4)
    assert close(0.0, 0.0, 0.0, 2.0)      # switches: none, and the testbed's 0-2


def test_the_calibration_simulates_the_loopback_demo():
    out = run('server_select.sim.calibration', '--part', 'loopback', '--seeds', '1',
              '--processes', '1')
    assert '| loopback switches | fleet |' in out, out
