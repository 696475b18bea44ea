"""A grouped scale cell run as its groups side by side (sim/scale.py) gives the figures of
the whole run: its groups share nothing, and every draw comes from a stream of its own."""

import json
import subprocess
import sys

import pytest

from server_select.sim import scale


def test_the_groups_of_a_cell_are_its_robots_dealt_in_turn_and_its_servers_in_blocks():
    assert scale.groups_of(5, 4, 2) == [([1, 3, 5], [1, 2]), ([2, 4], [3, 4])]


def test_a_group_alone_keeps_the_links_it_has_in_the_whole_field():
    whole, part = scale.field(6, 4, 10.0), scale.field(6, 4, 10.0, only=([2, 4], [3, 4]))
    assert sorted(h.name for h in part.hosts.values() if h.role != 'manager') == [
        'robot2', 'robot4', 'server3', 'server4']
    for pair in ('robot2', 'server3'), ('robot4', 'server4'):
        assert part.link(pair[0], pair[1], 1.0) == whole.link(pair[0], pair[1], 1.0)


@pytest.mark.parametrize('variant', ['fleet', 'prequal'])
def test_a_grouped_cell_side_by_side_gives_the_whole_runs_figures(variant, tmp_path):
    rows = []
    for whole in (True, False):
        out = tmp_path / ('whole.json' if whole else 'groups.json')
        done = subprocess.run(
            [sys.executable, '-m', 'server_select.sim.scale', '--cells', '12x4/2',
             '--seconds', '20', '--variants', variant, '--processes', '2', '--out', str(out)]
            + (['--whole'] if whole else []), stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT, universal_newlines=True, timeout=300)
        assert done.returncode == 0, done.stdout[-3000:]
        with open(str(out)) as stream:
            rows.append(json.load(stream)[0])
    whole, groups = rows
    assert (whole['parts'], groups['parts']) == (1, 2)
    assert whole['tasks'] > 100 and whole['decisions'] > 100, whole
    for key in ('events', 'tasks', 'failed', 'decisions'):
        assert groups[key] == whole[key], (key, rows)
    for key in ('mean_ms', 'probes_per_s_per_robot'):
        assert groups[key] == pytest.approx(whole[key], rel=1e-9), (key, rows)
