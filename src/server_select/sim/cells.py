"""Where the simulator's cells run (no rospy): on dask.distributed, an embedded local
cluster by default (nothing to set up), or a lab's machines that run ``dask-worker
tcp://HOST:8786`` (``--scheduler tcp://HOST:8786``; each worker needs this package and
its ROS package path, as ``make build`` gives).

A cell is one seeded run; its figures depend on its seed alone, so they come out the same
byte for byte whichever worker, on whichever machine, runs it, and in whatever order the
cells finish (reports sort them). A progress line says cells done, cells in all and the
time left.
"""

import contextlib
import logging
import os
import time

PROGRESS_EVERY = 10.0      # s between two progress lines at most
CHUNK = 8                  # cells a dask task runs at most (fewer tasks: less of dask's work)
SHARES = 4                 # dask tasks per worker at least, while there are cells enough


def add_arguments(parser):
    """The engine's options: ``--scheduler`` and ``--processes``."""
    parser.add_argument('--scheduler', metavar='tcp://HOST:8786',
                        help='run the cells on this dask scheduler\'s workers (default: an '
                        'embedded local cluster)')
    parser.add_argument('--processes', type=int, default=os.cpu_count() or 1,
                        help='workers of the embedded cluster (%(default)s)')


@contextlib.contextmanager
def client(scheduler=None, processes=None):
    """A dask ``Client`` of ``scheduler``, or of a local cluster of ``processes`` worker
    processes of one thread each (closed with the block)."""
    import dask
    from distributed import Client, LocalCluster
    # a worker samples its tasks' stacks every 10 ms by default: a third of a cell's time
    dask.config.set({'distributed.worker.profile.enabled': False,
                     'distributed.admin.tick.interval': '1s'})
    if scheduler:
        with Client(scheduler, timeout='20s') as connected:
            yield connected
        return
    with LocalCluster(n_workers=max(1, processes or 1), threads_per_worker=1, processes=True,
                      dashboard_address=':0', silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as connected:
        yield connected


def run(function, jobs, scheduler=None, processes=None, log=print):
    """Yield ``function(job)`` of every job as its cell finishes; ``log(line)`` hears the
    progress."""
    from distributed import as_completed
    jobs = list(jobs)
    progress = Progress(len(jobs), log)
    with client(scheduler, processes) as connected:
        workers = len(connected.scheduler_info().get('workers', ())) or processes or 1
        size = chunk_size(len(jobs), workers)
        chunks = [jobs[i:i + size] for i in range(0, len(jobs), size)]
        tasks = connected.map(_each, [function] * len(chunks), chunks, pure=False)
        for future in as_completed(tasks):
            for result in future.result():
                yield result
                progress.step()


def chunk_size(jobs, workers):
    """Cells a dask task runs: :data:`CHUNK`, or fewer, so that each of ``workers`` gets
    :data:`SHARES` tasks at least (a scale cell's 10 groups in chunks of 8 left one of two
    workers 8 and the other 2: 450 s where 5 and 5 take 270)."""
    return max(1, min(CHUNK, jobs // (SHARES * max(1, workers))))


def _each(function, chunk):
    return [function(job) for job in chunk]


class Progress(object):
    """``cells N of M, about T left`` every :data:`PROGRESS_EVERY` s, and at the end."""

    def __init__(self, total, log, clock=time.monotonic):
        self.total, self.log, self.clock = total, log, clock
        self.done, self.start = 0, clock()
        self._last = self.start

    def step(self):
        self.done += 1
        now = self.clock()
        if now - self._last < PROGRESS_EVERY and self.done < self.total:
            return
        self._last = now
        left = (now - self.start) / self.done * (self.total - self.done)
        self.log('cells %d of %d, %s' % (self.done, self.total, 'about %s left' % _duration(
            left) if self.done < self.total else 'done in %s' % _duration(now - self.start)))


def _duration(seconds):
    minutes, seconds = divmod(int(round(seconds)), 60)
    return '%d min %02d s' % (minutes, seconds) if minutes else '%d s' % seconds
