"""Parsers of node parameters (no rospy); the table of parameters is
:mod:`server_select.core.settings`.

Values arrive from the parameter server as whatever YAML made of them (a launch ``<arg>``
is a string, ``rosparam`` gives lists and numbers), so each parser accepts the forms a
user can reasonably type and raises :class:`ParamError` with a message naming the
parameter otherwise.
"""

import difflib
import math
import os
import re

MODES = ('select', 'fixed', 'local')      # a robot's ~mode


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


def parse_members(name, value):
    """A list of distinct ids that may be empty (``[]``, ``''``: learned at run time)."""
    if value in ('', [], ()) or (isinstance(value, str) and not value.strip().strip('[]').strip()):
        return []
    return parse_id_list(name, value)


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


def _float(name, value, kind):
    """``value`` as a float, or ParamError saying a ``kind`` number was expected."""
    if isinstance(value, bool):
        raise ParamError('%s: expected a %s number, got %r' % (name, kind, value))
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ParamError('%s: expected a %s number, got %r' % (name, kind, value))


def parse_non_negative(name, value):
    """A finite number >= 0."""
    number = _float(name, value, 'non-negative')
    if not 0 <= number < float('inf'):
        raise ParamError('%s: expected a non-negative number, got %r' % (name, value))
    return number


def parse_mode(name, value):
    """Robot task mode: ``select`` (follow the manager), ``fixed`` (paper baseline) or
    ``local`` (the robot processes its tasks itself)."""
    if value not in MODES:
        raise ParamError('%s: unknown mode %r, expected one of %s'
                         % (name, value, ', '.join(MODES)))
    return value


def parse_fixed_server(name, value, servers, mode):
    """The baseline server; required to be one of ``servers`` when mode is ``fixed``."""
    if mode != 'fixed' and value in (None, '', -1):
        return None
    if value in (None, ''):
        raise ParamError('%s: required when mode is fixed' % name)
    ident = parse_id(name, value)
    if mode == 'fixed' and ident not in servers:
        raise ParamError('%s: server %d is not in servers %s' % (name, ident, servers))
    return ident


def parse_positive_int(name, value):
    """A strictly positive integer."""
    return parse_positive(name, value, integer=True)


def parse_count(name, value):
    """A non-negative integer (``0`` usually meaning "no limit" or "the first")."""
    if value in (0, '0'):
        return 0
    return parse_positive(name, value, integer=True)


def parse_number(name, value):
    """Any finite number."""
    number = _float(name, value, 'finite')
    if not math.isfinite(number):
        raise ParamError('%s: expected a finite number, got %r' % (name, value))
    return number


def parse_bool(name, value):
    """``true``/``false`` (YAML booleans or the strings a launch file passes)."""
    if isinstance(value, bool):
        return value
    if isinstance(value, str) and value.strip().lower() in ('true', 'false'):
        return value.strip().lower() == 'true'
    raise ParamError('%s: expected true or false, got %r' % (name, value))


def parse_text(name, value):
    """A string (numbers given by YAML are turned back into their text)."""
    if isinstance(value, (list, dict)) or value is None:
        raise ParamError('%s: expected a string, got %r' % (name, value))
    return str(value)


def parse_path(name, value):
    """A file path; a leading ``~`` is the user's home (``fleet_key:=~/.ros/robot.key``:
    roslaunch passes the text as it is)."""
    return os.path.expanduser(parse_text(name, value))


def parse_names(name, value):
    """A non-empty list of strings: a YAML list or one string of names separated by commas
    and/or spaces."""
    if isinstance(value, str):
        value = value.replace(',', ' ').split()
    if not value or not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ParamError('%s: expected a list of names, got %r' % (name, value))
    return value


def parse_node_names(name, value):
    """A possibly empty list of node names (a YAML list, or one string)."""
    return [] if value in ('', None, []) else parse_names(name, value)


def parse_plugins(name, value):
    """A possibly empty list of ``module:Class`` names (a YAML list, or one string)."""
    if value in ('', None, []):
        return []
    specs = parse_names(name, value)
    bad = [s for s in specs if s.count(':') != 1 or not all(s.split(':'))]
    if bad:
        raise ParamError('%s: expected module:Class names, got %s' % (name, bad))
    return specs


def parse_publisher(name, value):
    """The name of the one node whose messages count; ``*`` (or empty) for any: None."""
    value = parse_text(name, value).strip()
    return None if value in ('', '*') else value


def parse_node_pattern(name, value):
    """A node name with ``{id}`` (``/robot{id}``); ``first`` as it is; ``*`` (or empty) for
    any node: None."""
    pattern = parse_publisher(name, value)
    if pattern == 'first':
        return pattern
    try:
        pattern and pattern.format(id=1)
    except (KeyError, IndexError, ValueError) as error:
        raise ParamError('%s: %r is not a node name with {id}: %s' % (name, pattern, error))
    return pattern


def one_of(*choices):
    """A parser accepting one of ``choices`` (strings)."""
    def parse(name, value):
        if value not in choices:
            raise ParamError('%s: %r is not one of %s' % (name, value, ', '.join(choices)))
        return value
    return parse


def nearest(name, valid):
    """The name in ``valid`` closest to ``name`` (what a typo meant, in any case:
    ``robot_Id`` means ``robot_id``), or None."""
    lowered = dict((v.lower(), v) for v in sorted(valid, reverse=True))
    near = difflib.get_close_matches(name.lower(), sorted(lowered), 1)
    return lowered[near[0]] if near else None
