"""The simulator's cells on dask.distributed: a local cluster of 2 workers, and a scheduler
given by address, give the figures a cell gives when run in this process, byte for byte;
the progress line counts the cells."""

import json

from distributed import LocalCluster

from server_select.sim import cells, league

CELL = ['--seeds', '2', '--scenarios', 'near_equal', '--variants', 'fleet,prequal',
        '--cases', 'herd', '--capacity-variants', 'static,fleet']


def here(args):
    """The figures of every cell of ``args``, run one by one in this process."""
    results = {'network': {}, 'capacity': {}}
    for job in league.jobs(args):
        for part, name, variant, seed, row, _ in league.run_cell(job):
            results[part].setdefault(name, {}).setdefault(variant, {})[seed] = row
    return json.dumps(results, sort_keys=True)


def test_cells_on_a_local_cluster_of_two_workers_give_the_figures_of_this_process(tmp_path):
    args = league.parse(CELL + ['--processes', '2', '--out', str(tmp_path)])
    lines = []
    results, cpu = league.run(args, lines.append)
    assert json.dumps(results, sort_keys=True) == here(args)
    assert cpu > 0
    assert lines[-1].startswith('cells 8 of 8, done in'), lines


def test_the_league_runs_on_the_scheduler_it_is_given(tmp_path, capsys):
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=':0') as cluster:
        assert league.main(CELL + ['--scheduler', cluster.scheduler_address,
                                   '--out', str(tmp_path)]) == 0
    assert cluster.scheduler_address in capsys.readouterr().out
    written = json.loads((tmp_path / 'league.json').read_text())
    expected = json.loads(here(league.parse(CELL)))
    cells_seen = 0
    for part, scenarios in expected.items():   # (the report adds ratios to what it writes)
        for name, variants in scenarios.items():
            for variant, seeds in variants.items():
                for seed, row in seeds.items():
                    kept = dict((k, written[part][name][variant][seed][k]) for k in row)
                    assert json.dumps(kept, sort_keys=True) == json.dumps(row, sort_keys=True)
                    cells_seen += 1
    assert cells_seen == 8


def test_the_progress_line_says_cells_done_and_the_time_left():
    now, lines = [0.0], []
    progress = cells.Progress(4, lines.append, clock=lambda: now[0])
    for _ in range(3):
        now[0] += 5.0
        progress.step()
    assert lines == ['cells 2 of 4, about 10 s left']
    now[0] += 65.0
    progress.step()
    assert lines[-1] == 'cells 4 of 4, done in 1 min 20 s'


def test_few_cells_are_spread_over_every_worker_and_many_go_in_chunks():
    """A scale cell's 10 groups on 2 workers go one a task (5 each, not 8 and 2); a league's
    2,100 cells go 8 a task; one worker or one cell still makes whole tasks."""
    assert cells.chunk_size(10, 2) == 1
    assert cells.chunk_size(2100, 2) == cells.CHUNK
    assert cells.chunk_size(64, 2) == cells.CHUNK
    assert cells.chunk_size(40, 2) == 5
    assert cells.chunk_size(1, 0) == 1
