"""The soak's nemesis: each fault of the schedule done to the fleet at its planned time,
with what happened logged (wall-clock times; the analysis reads faults from this log, and
everything else from the bags and the nodes' logs).

An event is ``{kind, target, planned, start, end, bound, detail}``: the fault's window is
``[start, end]`` (for a kill, until the restarted node was started again; a roscore, until
the new master answers) and the fleet must be back ``bound`` s after ``end``. A robot's
lives end at ``stops`` (node name, time it was gone, time it was SIGKILLed or None): a
restarted robot counts its tasks from 1.
"""

import itertools
import os
import signal
import subprocess
import threading
import time

from server_select.core.util.procs import stop_groups, wait_until
from server_select.ros import key_reload
from server_select.soak import plan
from server_select.soak.fleet import BURST_RATE

MAIN_NODES = ['manager'] + ['server%d' % s for s in plan.SERVERS] + \
    ['robot%d' % r for r in plan.ROBOTS]


class Nemesis(object):
    """Does ``faults`` (plan.Fault, scenario times) to ``fleet`` (a SoakFleet) on testbed
    ``tb``; ``roscore`` starts a master and returns its process."""

    def __init__(self, fleet, tb, roscore, say=print):
        self.fleet, self.tb, self.roscore, self.say = fleet, tb, roscore, say
        self.core = None
        self.events, self.stops = [], []
        self.over = 0.0     # scenario s by which the faults done so far are over, bound included

    def run(self, faults):
        """Each fault at its time; faults planned for one time (a wave of the short soak)
        at once, each in a thread of its own; the first error of a wave raised."""
        for at, wave in itertools.groupby(faults, key=lambda f: f.at):
            wave = list(wave)
            # not before the faults before are over, whatever their plan said (a restart
            # on a loaded host takes longer: one that met a master restart lost the
            # parameters its launch had set, and never served)
            self.tb.sleep_until(max(at, self.over))
            errors = []
            threads = [threading.Thread(target=self._guarded, args=(f, errors), name=f.kind)
                       for f in wave]
            for thread in threads:
                thread.start()
            for thread in threads:
                thread.join()
            self.events.sort(key=lambda e: e['start'])
            ends = [e['end'] - self.tb.t0 + e['bound'] for e in self.events]
            self.over = max([self.over] + ends)
            if errors:
                raise errors[0]

    def _guarded(self, fault, errors):
        try:
            self._do(fault)
        except Exception as error:   # raised by run() once the wave is over
            errors.append(error)

    def _do(self, fault):
        start = time.time()
        detail = getattr(self, fault.kind)(fault)
        end = time.time()
        if isinstance(detail, tuple):      # the fault's window ended before its return
            detail, end = detail
        event = dict(kind=fault.kind, target=fault.target, planned=self.tb.t0 + fault.at,
                     start=start, end=end, bound=fault.bound, detail=detail)
        self.events.append(event)
        self.say('%7.1f s  %-12s %-4s %5.1f s  %s' % (
            start - self.tb.t0, fault.kind, fault.target or '', event['end'] - start,
            event['detail']))

    def _killed(self, name, down):
        """SIGKILL node ``name``, its launch stopped, started again after ``down`` s."""
        pid = self.fleet.signal(name, signal.SIGKILL)
        killed = time.time()
        time.sleep(down)
        self.fleet.stop(name)
        self.stops.append((name, time.time(), killed))
        self.fleet.start(name)
        # the fault lasts until the new copy is registered
        wait_until(lambda: self.fleet.pid(name) not in (None, pid), 60.0, period=0.3)
        return 'pid %s killed' % pid

    def server_kill(self, fault):
        return self._killed('server%d' % fault.target, fault.length)

    def manager_kill(self, fault):
        return self._killed('manager', fault.length)

    def robot_kill(self, fault):
        return self._killed('robot%d' % fault.target, fault.length)

    def server_stop(self, fault):
        name = 'server%d' % fault.target
        pid = self.fleet.signal(name, signal.SIGSTOP)
        try:
            time.sleep(fault.length)
        finally:
            _kill(pid, signal.SIGCONT)
        return 'pid %s stopped' % pid

    def link_down(self, fault):
        self.tb.sleep_until(fault.at + fault.length)     # the link emulator does it
        return 'every link of server%d' % fault.target

    def roscore_kill(self, fault):
        master, rosout = self.fleet.master.master_pid(), self.fleet.pid('/rosout')
        stop_groups([self.core], signal.SIGKILL, 5.0)
        for pid in (master, rosout):
            _kill(pid, signal.SIGKILL)
        time.sleep(fault.length)
        self.core = self.roscore()
        up = time.time()
        self.fleet.start_recorder(MAIN_NODES)
        return 'master pid %s, rosout pid %s' % (master, rosout), up

    def overload(self, fault):
        bursts = ['robot%d' % r for r in plan.BURST_ROBOTS]
        for name in bursts:
            self.fleet.start(name)
        time.sleep(fault.length)
        stop_groups([self.fleet.procs.pop(name) for name in bursts])
        self.stops.extend((name, time.time(), None) for name in bursts)
        return '%s at %g frames/s each' % (', '.join(bursts), BURST_RATE)

    def intruder(self, fault):
        proc = self.fleet.start_intruder(fault.length)
        try:
            proc.wait(fault.length + 60.0)
        except subprocess.TimeoutExpired:       # it hangs: stopped, and said
            stop_groups([proc], signal.SIGKILL, 5.0)
            return 'did not end within 60 s of its time: killed'
        return 'sent %s' % self.fleet.intruder_said()

    def key_rotation(self, _fault):
        """The fleet's next key, with every node serving: in passes (plan.KeyRing), each
        pass the key files rewritten and every node told to read them again; the fault
        lasts until every node has said it did. An error names a node that did not."""
        passes, told = self.fleet.keys.passes(), []
        for move in passes:
            move()
            self.fleet.install_keys()
            answers = self.fleet.reload_keys()
            lines, good = key_reload.report(answers)
            if not good:
                raise RuntimeError('key rotation, %s: %s' % (move.__name__, '; '.join(lines)))
            told.append(len(answers))
        steps = ' + '.join('%s (%d nodes)' % (move.__name__.replace('_', ' '), n)
                           for move, n in zip(passes, told))
        return '%s; signing with key %d' % (steps, self.fleet.keys.index + 1)


def _kill(pid, sig):
    if pid is not None:
        try:
            os.kill(pid, sig)
        except ProcessLookupError:
            pass
