"""The league's pure parts: runs added to an --out that has some, and its tables."""

from server_select.bench.league import merge
from server_select.bench.league_report import capacity_table, network_table


def row(variant, load, repeat, goodput=1.0, capacity=2.0, work=None):
    return dict(variant=variant, load=load, repeat=repeat, goodput=goodput, capacity=capacity,
                failed=0, mean=0.5, p99=1.0, switches=1.0, extra=0.1, wanted=0.9, work=work)


def test_more_runs_keep_the_runs_already_there():
    old = {'network': {'crossing': [{}]},
           'capacity': {'crowd': [row('fleet', 1, 0), row('static', 1, 0)]}}
    new = {'capacity': {'crowd': [row('fleet', 1, 1), row('fleet', 1, 0, goodput=1.5)]}}
    merged = merge(old, new)
    assert merged['network'] == {'crossing': [{}]}          # not re-run: kept
    rows = merged['capacity']['crowd']
    assert sorted((r['variant'], r['repeat'], r['goodput']) for r in rows) == [
        ('fleet', 0, 1.5), ('fleet', 1, 1.0), ('static', 0, 1.0)]   # a re-made run wins


def test_capacity_table_gives_goodput_as_a_share_and_the_median_of_runs():
    text = capacity_table([row('fleet', 2, r, goodput=g) for r, g in enumerate((1.0, 1.8, 1.2))]
                          + [row('static', 2, 0, goodput=1.0)])
    lines = text.splitlines()
    assert lines[0].startswith('| load | variant | runs | goodput % of capacity')
    assert lines[2].startswith('| 2x | static | 1 | 50 |')      # static first, as listed
    assert lines[3].startswith('| 2x | fleet | 3 | 60 (50-90) |')


def test_goodput_is_also_given_against_what_the_static_assignments_servers_did():
    # the static assignment's servers finished 1.6 and 2.0 tasks/s in repeats 0 and 1
    text = capacity_table([row('static', 2, 0, goodput=0.2, work=1.6),
                           row('static', 2, 1, goodput=0.2, work=2.0),
                           row('fleet', 2, 0, goodput=1.6, work=1.7),
                           row('fleet', 2, 1, goodput=1.8, work=1.8)])
    lines = text.splitlines()
    assert "goodput % of static's work" in lines[0]
    # fleet: 1.6 / 1.6 and 1.8 / 2.0 -> 100 and 90, median 95; of capacity 2.0: 80 and 90
    assert lines[3].startswith("| 2x | fleet | 2 | 85 (80-90) | 95 (90-100) |")


def test_network_table_gives_the_mean_to_the_oracle_of_the_same_run():
    def figures(mean):
        return dict(mean=mean, p99=2 * mean, failed=0, switches=1.0,
                    reaction=0.5, extra=0.0, probes=10.0, robot_cpu=2.0)
    runs = [{'oracle_fleet': figures(0.010), 'prequal': figures(0.012)},
            {'oracle_fleet': figures(0.020), 'prequal': figures(0.021)}]
    lines = network_table(runs).splitlines()
    assert lines[0].startswith('| variant | runs | mean ms | p99 ms | mean / oracle | failed |')
    assert lines[3].startswith('| prequal | 2 | 16.50 (12.00-21.00) | 33.0 (24.0-42.0) | '
                               '1.125 (1.050-1.200) |')
