"""Checked fields of a scenario file: numbers, and a server host's hang and work times
(no rospy)."""


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
