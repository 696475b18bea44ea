"""A host's own work: a process that uses a given share of a core, as a robot's SLAM or
camera driver would (no rospy).

``python -m server_select.testbed.busy --share 0.05`` runs until stopped, using 5 % of one
core: it computes in slices of ``--slice`` s of its own CPU time and sleeps between them
so that its CPU time keeps pace with ``share`` x the wall-clock time. In a host with a
CPU limit it competes with the host's nodes for the host's quota, as a real robot's work
does; where the quota leaves it less than ``share`` it takes what it gets and lets the
rest go: it never runs more than ``catch_up`` s of wall time behind its pace (work a
robot missed is not done later at double speed).

A scenario host's ``busy: 0.5`` starts one with half of the host's CPU (``0.5 x cpu``, or
of one core where the host has no limit).
"""

import argparse
import signal
import sys
import time


def burn(share, until, slice_s=0.001, catch_up=0.05, clock=time.monotonic,
         cpu=time.process_time, sleep=time.sleep):
    """Use ``share`` of a core until ``until()`` is true; returns the CPU time used."""
    if not 0.0 < share <= 1.0:
        raise ValueError('a busy share must be in (0, 1], got %r' % (share,))
    start_wall, start_cpu = clock(), cpu()
    used = 0.0
    while not until():
        target = cpu() + slice_s
        while cpu() < target:
            pass
        used = cpu() - start_cpu
        ahead = start_wall + used / share - clock()    # wall time this much CPU is worth
        if ahead > 0:
            sleep(ahead)
        elif ahead < -catch_up:                         # behind: forgive all but catch_up
            start_wall += -ahead - catch_up
    return used


def command(host):
    """The argv of a scenario host's own work (a Host with ``busy``)."""
    share = host.busy * min(1.0, host.cpu or 1.0)
    return [sys.executable, '-m', 'server_select.testbed.busy', '--share', '%.4f' % share]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--share', type=float, required=True, help='of one core, (0, 1]')
    parser.add_argument('--slice', type=float, default=0.001, help='CPU s per slice')
    parser.add_argument('--seconds', type=float, default=0.0, help='0: until stopped')
    args = parser.parse_args(argv)
    stopped = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stopped.append(True))
    end = time.monotonic() + args.seconds if args.seconds > 0 else float('inf')
    print('busy: using %.4f of a core' % args.share, flush=True)   # started: at its pace now
    burn(args.share, lambda: stopped or time.monotonic() >= end, args.slice)
    return 0


if __name__ == '__main__':
    sys.exit(main())
