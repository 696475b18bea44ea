"""Validation of node parameters.

Values arrive from the parameter server as whatever YAML made of them (a launch ``<arg>``
is a string, ``rosparam`` gives lists and numbers), so each parser accepts the forms a
user can reasonably type and raises :class:`ParamError` with a message naming the
parameter otherwise.
"""

import re

MODES = ('select', 'fixed', 'local')


class ParamError(ValueError):
    """A parameter value that the node cannot run with."""


def parse_id(name, value):
    """One non-negative integer id (``3`` or ``"3"``)."""
    if isinstance(value, bool):
        raise ParamError('%s: expected a non-negative integer id, got %r' % (name, value))
    if isinstance(value, int):
        ident = value
    elif isinstance(value, str) and value.strip().isdigit():
        ident = int(value.strip())
    else:
        raise ParamError('%s: expected a non-negative integer id, got %r' % (name, value))
    if ident < 0:
        raise ParamError('%s: ids must be non-negative, got %d' % (name, ident))
    return ident


def parse_id_list(name, value):
    """A non-empty list of distinct ids.

    Accepts a YAML list (``[1, 2, 3]``), a single id, or a string of ids separated by
    commas and/or spaces (``"1,2,3"``, ``"1 2 3"``, ``"[1, 2, 3]"``). Order is kept.
    """
    if isinstance(value, (list, tuple)):
        items = list(value)
    elif isinstance(value, str):
        items = [tok for tok in re.split(r'[\s,]+', value.strip().strip('[]')) if tok]
    else:
        items = [value]
    if not items:
        raise ParamError('%s: expected a non-empty list of ids, got %r' % (name, value))
    ids = [parse_id(name, item) for item in items]
    duplicates = sorted({i for i in ids if ids.count(i) > 1})
    if duplicates:
        raise ParamError('%s: duplicate ids %s in %r' % (name, duplicates, value))
    return ids


def parse_positive(name, value, integer=False):
    """A strictly positive number (int when ``integer``)."""
    kind = 'integer' if integer else 'number'
    if isinstance(value, bool):
        raise ParamError('%s: expected a positive %s, got %r' % (name, kind, value))
    try:
        number = int(value) if integer else float(value)
    except (TypeError, ValueError):
        raise ParamError('%s: expected a positive %s, got %r' % (name, kind, value))
    if integer and isinstance(value, float) and value != number:
        raise ParamError('%s: expected a positive integer, got %r' % (name, value))
    if not number > 0 or number != number or number == float('inf'):
        raise ParamError('%s: expected a positive %s, got %r' % (name, kind, value))
    return number


def parse_non_negative(name, value):
    """A finite number >= 0."""
    if isinstance(value, bool):
        raise ParamError('%s: expected a non-negative number, got %r' % (name, value))
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ParamError('%s: expected a non-negative number, got %r' % (name, value))
    if not 0 <= number < float('inf'):
        raise ParamError('%s: expected a non-negative number, got %r' % (name, value))
    return number


def parse_mode(name, value):
    """Robot task mode: ``select`` (follow the manager), ``fixed`` (paper baseline) or
    ``local`` (the robot processes its tasks itself)."""
    if value not in MODES:
        raise ParamError('%s: unknown mode %r, expected one of %s' % (name, value, ', '.join(MODES)))
    return value


def parse_fixed_server(name, value, servers, mode):
    """The baseline server; required to be one of ``servers`` when mode is ``fixed``."""
    if mode != 'fixed' and value in (None, '', -1):
        return None
    if value in (None, ''):
        raise ParamError('%s: required when mode is fixed' % name)
    ident = parse_id(name, value)
    if ident not in servers:
        raise ParamError('%s: server %d is not in servers %s' % (name, ident, servers))
    return ident
