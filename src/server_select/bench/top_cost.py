"""What the live view costs (``make bench-top``): ``top``'s CPU and memory beside a fleet.

Each run: a roscore of its own and ``demo.launch profile:=fleet`` with ``--robots`` robots
and ``--servers`` servers (sort tasks at the default rate), then ``top`` in a terminal of its
own (a pseudo-terminal of 140 x 60, its screen read and thrown away, as a terminal
would), redrawing as it does; after ``--warmup`` s, its CPU (% of one core) and RSS over
``--seconds`` s, and the robots' mean CPU beside it. ``--repeats`` runs; printed: each run
and the median (min-max). Nothing is asserted.
"""

import fcntl
import os
import pty
import statistics
import struct
import sys
import tempfile
import termios
import threading
import time

from server_select.bench import cli
from server_select.bench.harness import Roscore, launched
from server_select.core.util.procs import measure, wait_until
from server_select.core.util.tables import markdown_table

ROWS, COLUMNS = 60, 140


def start_top(servers):
    """``(pid, fd)`` of ``top`` running in a pseudo-terminal whose output is drained."""
    pid, fd = pty.fork()
    if pid == 0:          # the child: top, as a user starts it
        os.environ['TERM'] = 'xterm'
        os.execv(sys.executable, [sys.executable, '-c', 'import sys; from server_select.nodes.'
                                  'top import main; sys.exit(main())',
                                  '--servers', ','.join(str(s) for s in servers)])
    fcntl.ioctl(fd, termios.TIOCSWINSZ, struct.pack('HHHH', ROWS, COLUMNS, 0, 0))

    def drain():
        try:
            while os.read(fd, 65536):
                pass
        except OSError:       # the child closed its end
            pass
    threading.Thread(target=drain, daemon=True).start()
    return pid, fd


def end_top(pid, fd):
    """Quit ``top`` its own way (``q``), killed if it does not end within 10 s."""
    try:
        os.write(fd, b'q')
        if not wait_until(lambda: os.waitpid(pid, os.WNOHANG)[0] != 0, 10.0):
            os.kill(pid, 9)
            os.waitpid(pid, 0)
    except OSError:       # it had ended (and was reaped) already
        pass
    os.close(fd)


def one_run(options, work, repeat):
    """``{'top_cpu', 'top_rss', 'robot_cpu'}`` of one run."""
    robots = ['/robot%d' % r for r in range(1, options.robots + 1)]
    args = ['output:=log', 'profile:=fleet', 'n_robots:=%d' % options.robots,
            'n_servers:=%d' % options.servers]
    with Roscore(work), launched('demo.launch', args, os.path.join(work, 'run%d.log' % repeat),
                                 nodes=robots, timeout=120.0) as robot_pids:
        pid, fd = start_top(range(1, options.servers + 1))
        try:
            time.sleep(options.warmup)        # it hears every server and robot
            usage = measure([pid] + list(robot_pids.values()), options.seconds)
            if os.waitpid(pid, os.WNOHANG)[0] != 0:
                raise RuntimeError('top ended before the measurement did')
        finally:
            end_top(pid, fd)
    robot_cpu = [usage[p]['cpu_percent'] for p in robot_pids.values() if p in usage]
    return {'top_cpu': usage[pid]['cpu_percent'], 'top_rss': usage[pid]['rss_mb'],
            'robot_cpu': statistics.mean(robot_cpu) if robot_cpu else float('nan')}


def main(argv=None):
    parser = cli.parser(__doc__)
    parser.add_argument('--robots', type=int, default=20)
    parser.add_argument('--servers', type=int, default=10)
    parser.add_argument('--warmup', type=float, default=15.0)
    parser.add_argument('--seconds', type=float, default=60.0)
    parser.add_argument('--repeats', type=int, default=3)
    options = parser.parse_args(argv)
    work = tempfile.mkdtemp(prefix='top_cost_')
    runs = []
    for repeat in range(1, options.repeats + 1):
        runs.append(one_run(options, work, repeat))
        print('run %d of %d: %s' % (repeat, options.repeats, runs[-1]), file=sys.stderr,
              flush=True)
    rows = [[what] + ['%.2f' % r[key] for r in runs] +
            ['%.2f (%.2f-%.2f)' % (statistics.median(r[key] for r in runs),
                                   min(r[key] for r in runs), max(r[key] for r in runs))]
            for what, key in (('top CPU % of a core', 'top_cpu'), ('top RSS MiB', 'top_rss'),
                              ('a robot\'s CPU % (mean)', 'robot_cpu'))]
    text = markdown_table([''] + ['run %d' % (i + 1) for i in range(len(runs))] +
                          ['median (min-max)'], rows)
    cli.write(options.out, 'top_cost.json', runs)
    cli.write(options.out, 'top_cost.md', text + '\n')
    print('top beside a fleet of %d robots x %d servers (%g s each run; logs in %s):\n%s'
          % (options.robots, options.servers, options.seconds, work, text))
    return 0


if __name__ == '__main__':
    sys.exit(main())
