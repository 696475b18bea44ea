"""Checked fields of a scenario file: numbers, a server host's hang and work times, and a
host's resources (no rospy)."""

DEFAULT_CPU_PERIOD_MS = 100.0
# A Raspberry Pi 3 Model B (Cortex-A53, 4 x 1.2 GHz, 1 GB) as a scenario host's ``like:``.
# One Pi 3 core does about a tenth of this host's core (an AMD EPYC at 2.6 GHz) for
# integer-heavy interpreted code: a Pi 2 took 11.2x as long as a Core i3-3220 on an
# integer benchmark and 10.4x on a mixed one (J. Whitham, "Relative speed of Raspberry Pi,
# Pi 2, and desktop PC", 2015); a Pi 3 is 1.4-1.6x a Pi 2 (the Raspberry Pi Foundation's
# figures, confirmed by Dhrystone runs); a current server core is taken to do 1.1-1.5x an
# i3-3220's single-thread work (assumed: the host names no closer model). 11.2 / 1.5 x
# (1.1-1.5): 8-11x, taken as 10x (bench-robot's --pi-share changes it for a run).
# A node is one Python process (one core at a time under the GIL): the host gets one Pi
# core, evenly (10 ms periods: the kernel's least quota is 1 ms), and the Pi's memory.
PI3 = {'cpu': 0.10, 'cpu_period': 10.0, 'memory': 1024}
LIKE = {'pi3': PI3}


class ScenarioError(ValueError):
    """A scenario file that cannot be used; the message says where."""


def hang_times(spec, name):
    """``[[from, to], ...]`` (s) in time order, as tuples."""
    where = 'hosts: %s hang' % name
    if spec is None:
        return ()
    if not isinstance(spec, list):
        raise ScenarioError('%s: expected a list of [from, to] pairs' % where)
    result, last = [], 0.0
    for item in spec:
        if not isinstance(item, list) or len(item) != 2:
            raise ScenarioError('%s: expected [from, to], got %r' % (where, item))
        a = number(item[0], where, last)
        result.append((a, number(item[1], where, a)))
        last = result[-1][1]
    return tuple(result)


def work_times(spec, name):
    """``[{at: s, delay: ms}, ...]`` in time order, as ``(at s, delay s)`` tuples."""
    where = 'hosts: %s work' % name
    if spec is None:
        return ()
    if not isinstance(spec, list):
        raise ScenarioError('%s: expected a list of {at, delay} mappings' % where)
    result, last = [], 0.0
    for item in spec:
        if not isinstance(item, dict) or set(item) != {'at', 'delay'}:
            raise ScenarioError('%s: expected {at: s, delay: ms}, got %r' % (where, item))
        last = number(item['at'], where, last)
        result.append((last, number(item['delay'], where, 0.0) / 1e3))
    return tuple(result)


def number(value, where, minimum=None, maximum=None):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ScenarioError('%s: expected a number, got %r' % (where, value))
    value = float(value)
    if value != value or (minimum is not None and value < minimum) or \
            (maximum is not None and value > maximum):
        raise ScenarioError('%s: %g is out of range' % (where, value))
    return value


def resources(name, role, spec):
    """A host's ``(cpu, cpu_period ms, memory MiB, busy)`` from its spec (``like`` first,
    then what the spec sets)."""
    like = spec.get('like')
    if like is not None and like not in LIKE:
        raise ScenarioError('hosts: %s is like %r; known: %s' % (name, like, ', '.join(LIKE)))
    spec = dict(LIKE.get(like, {}), **dict((k, v) for k, v in spec.items() if k != 'like'))
    cpu = spec.get('cpu')
    if cpu is not None:
        cpu = number(cpu, 'hosts: %s cpu (share of one core)' % name, 0.01, 64.0)
    period = number(spec.get('cpu_period', DEFAULT_CPU_PERIOD_MS),
                    'hosts: %s cpu_period (ms)' % name, 1.0, 1000.0)
    memory = spec.get('memory')
    if memory is not None:
        memory = number(memory, 'hosts: %s memory (MiB)' % name, 16.0)
    busy = number(spec.get('busy', 0.0), 'hosts: %s busy (share of its CPU)' % name, 0.0, 1.0)
    if role == 'manager' and (cpu is not None or memory is not None or busy):
        raise ScenarioError('hosts: the manager host has no CPU limit')
    if memory is not None and cpu is None:
        raise ScenarioError('hosts: %s has a memory limit but no cpu share' % name)
    return cpu, period, memory, busy
