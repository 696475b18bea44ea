"""The league's columns, one set for the simulated league (``sim/report.py``) and the
testbed's (``bench/league_report.py``): each figure's key in a run's results, its heading,
format and scale (what the figure is multiplied by to be shown). A report shows the
columns its runs have a figure for (the testbed measures the robots' CPU, the simulator
does not)."""

# a network scenario: one row per variant
NETWORK = (('mean', 'mean ms', '%.2f', 1e3), ('p99', 'p99 ms', '%.1f', 1e3),
           ('ratio', 'mean / oracle', '%.3f', 1), ('failed', 'failed', '%.0f', 1),
           ('switches', 'switches /min /robot', '%.2f', 1),
           ('reaction', 'reaction s', '%.2f', 1),
           ('reaction_felt', 'reaction felt s', '%.2f', 1),
           ('extra', 'extra sends %', '%.1f', 100), ('probes', 'probes /s /robot', '%.1f', 1),
           ('robot_cpu', 'robot CPU %', '%.1f', 1))
# a capacity case: one row per variant (and load)
CAPACITY = (('share', 'goodput % of capacity', '%.0f', 100),
            ('of_static', "goodput % of static's work", '%.0f', 100),
            ('wanted', 'work still wanted %', '%.0f', 100),
            ('failed', 'failed', '%.0f', 1), ('mean', 'mean ms', '%.0f', 1e3),
            ('p99', 'p99 ms', '%.0f', 1e3),
            ('switches', 'switches /min /robot', '%.1f', 1),
            ('settled', 'settled switches /min /robot', '%.1f', 1),
            ('extra', 'extra sends %', '%.0f', 100), ('probes', 'probes /s /robot', '%.1f', 1))


def shown(columns, runs):
    """The ``columns`` some run of ``runs`` (dicts) has a figure for."""
    runs = list(runs)
    return [c for c in columns if any(r.get(c[0]) is not None for r in runs)]
