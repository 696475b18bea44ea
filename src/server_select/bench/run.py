"""``make bench``: the second paper's tables and the package's throughput, measured here.

Runs against a roscore it starts on a free port; every benchmark prints figures and
writes JSON to ``--out``, and ``REPORT.md`` puts them beside the paper's numbers (labelled
as the paper's). Nothing here asserts a timing. ``--tiny`` runs each benchmark once in a
minimal configuration (the smoke test of ``make test``).
"""

import collections
import json
import os
import sys
import tempfile
import time

from server_select.bench import cli
from server_select.bench import emulator, measure
from server_select.bench.harness import ReportListener, Roscore
from server_select.bench.report import SECTIONS, report
from server_select.ros.paths import package_file
from server_select.testbed.netns import available

# name on the command line -> (results key, benchmark(tiny, log, listener, area))
BENCHMARKS = collections.OrderedDict([
    ('table2', ('table2', lambda tiny, log, listener, area: measure.bench_table2(tiny))),
    ('probe', ('probe_vs_echo', lambda tiny, log, listener, area:
               measure.bench_probe_vs_echo(tiny, log))),
    ('table1', ('table1', lambda tiny, log, listener, area:
                measure.bench_table1(tiny, log, listener, area))),
    ('sort', ('sort_throughput', lambda tiny, log, listener, area:
              measure.bench_sort_throughput(tiny, log, listener))),
    ('image', ('image_throughput', lambda tiny, log, listener, area:
               measure.bench_image_throughput(tiny, log, listener, area))),
    ('breakdown', ('sort_breakdown', lambda tiny, log, listener, area:
                   measure.bench_sort_breakdown(tiny, log, listener))),
])


def run_on_roscore(wanted, tiny, out):
    """The benchmarks that need a master, each timed on stderr."""
    results = collections.OrderedDict()
    area = package_file('config', 'search_area.yaml')
    log = os.path.join(out, 'bench_nodes.log')
    open(log, 'w').close()
    with tempfile.TemporaryDirectory(prefix='bench') as tmp, Roscore(tmp):
        import rospy
        rospy.init_node('bench', anonymous=True, disable_signals=True)
        listener = ReportListener()
        for name, (key, bench) in BENCHMARKS.items():
            if wanted(name):
                started = time.monotonic()
                results[key] = bench(tiny, log, listener, area)
                print('bench: %s done in %.0f s' % (name, time.monotonic() - started),
                      file=sys.stderr, flush=True)
        rospy.signal_shutdown('benchmarks done')
    return results


def run_emulated():
    ok, why = available()
    if not ok:
        print('bench: emulated link skipped: %s' % why, file=sys.stderr)
        return None
    with tempfile.TemporaryDirectory(prefix='bench_emulated') as work:
        return [emulator.measure_case(rtt, 0.0, work, 300, 100) for rtt in (5.0, 20.0)]


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--tiny', action='store_true', help='one minimal run of each benchmark')
    parser.add_argument('--only', default='', help='comma-separated subset: %s, emulated (the '
                        'report then also shows earlier results found in --out)'
                        % ', '.join(BENCHMARKS))
    args = parser.parse_args(argv)
    only = set(filter(None, args.only.split(',')))

    def wanted(name):
        return not only or name in only
    os.makedirs(args.out, exist_ok=True)
    results = run_on_roscore(wanted, args.tiny, args.out)
    if wanted('emulated') and not args.tiny:
        results['emulated'] = run_emulated()
    for key, value in results.items():
        if value is not None:
            with open(os.path.join(args.out, '%s.json' % key), 'w') as stream:
                json.dump(value, stream, indent=1)
    if only:  # the report also shows what earlier runs left in --out
        for key, _ in SECTIONS:
            path = os.path.join(args.out, '%s.json' % key)
            if not results.get(key) and os.path.exists(path):
                with open(path) as stream:
                    results[key] = json.load(stream)
    text = report(results)
    with open(os.path.join(args.out, 'REPORT.md'), 'w') as stream:
        stream.write(text + '\n')
    print(text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
