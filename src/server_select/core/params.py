"""Node parameters: how each is parsed, and its default, in one table (no rospy).

Values arrive from the parameter server as whatever YAML made of them (a launch ``<arg>``
is a string, ``rosparam`` gives lists and numbers), so each parser accepts the forms a
user can reasonably type and raises :class:`ParamError` with a message naming the
parameter otherwise. :data:`PARAMS` is the one place a default is written: nodes read
parameters through it (``server_select.ros.node.param``), launch files leave an argument
empty to mean "the node's default", and the evaluation takes its defaults from it.
"""

import collections
import math
import re

from server_select.core.selection import MODES


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
    if ident not in servers:
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


def parse_names(name, value):
    """A non-empty list of strings: a YAML list or one string of names separated by commas
    and/or spaces."""
    if isinstance(value, str):
        value = value.replace(',', ' ').split()
    if not value or not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ParamError('%s: expected a list of names, got %r' % (name, value))
    return value


def parse_publisher(name, value):
    """The name of the one node whose messages count; ``*`` (or empty) for any: None."""
    value = parse_text(name, value).strip()
    return None if value in ('', '*') else value


def one_of(*choices):
    """A parser accepting one of ``choices`` (strings)."""
    def parse(name, value):
        if value not in choices:
            raise ParamError('%s: %r is not one of %s' % (name, value, ', '.join(choices)))
        return value
    return parse


REQUIRED = object()

Param = collections.namedtuple('Param', 'default parse doc')

DEFAULT_CASCADE = 'haarcascade_frontalface_default.xml'

# Every node parameter: default (REQUIRED: none), parser, meaning. A flat table.
PARAMS = {
    'robot_id': Param(REQUIRED, parse_id, "this robot's id"),
    'server_id': Param(REQUIRED, parse_id, "this server's id"),
    'robots': Param(REQUIRED, parse_id_list, 'ids of the robots'),
    'servers': Param(REQUIRED, parse_id_list, 'ids of the servers'),
    'mode': Param('select', parse_mode, 'select (follow the manager), fixed or local'),
    'fixed_server': Param(None, parse_id, 'target in fixed mode (default: first server)'),
    'probe_rate': Param(1.0, parse_positive, 'probes per second to each server (Hz)'),
    'probe_timeout': Param(0.5, parse_positive, 'a probe without answer after this fails (s)'),
    'sort_tasks': Param(True, parse_bool, 'send sort tasks'),
    'task_rate': Param(2.0, parse_positive, 'sort tasks per second (Hz)'),
    'task_size': Param(1000, parse_positive_int, 'values per sort task'),
    'task_timeout': Param(2.0, parse_positive, 'a task without result after this fails (s)'),
    'tasks': Param(0, parse_count, 'stop each stream after this many tasks (0: never)'),
    'start_delay': Param(0.0, parse_non_negative, 'seconds to wait before the first task'),
    'summary_period': Param(10.0, parse_positive, 'period of the log summary (s)'),
    'seed': Param(None, parse_id, 'task data random seed (default: the robot id)'),
    'image_source': Param('', parse_text, 'folder, video file or search:<area.yaml>'),
    'frame_rate': Param(10.0, parse_positive, 'camera frames offloaded per second (Hz)'),
    'image_encoding': Param('bgr8', one_of('bgr8', 'rgb8', 'mono8'), 'encoding of sent frames'),
    'robot_index': Param(0, parse_count, "this robot's strip of a search area"),
    'robot_count': Param(1, parse_positive_int, 'number of strips of a search area'),
    'speed': Param(200.0, parse_positive, 'sweep speed over a search area (area pixels/s)'),
    'merge_radius': Param(150.0, parse_positive, 'detections this close are one target (px)'),
    'detector': Param('haar', one_of('haar', 'hog'), 'Haar cascade or HOG people detector'),
    'cascade': Param(DEFAULT_CASCADE, parse_text, 'cascade file name or path'),
    'scale_factor': Param(1.2, parse_positive, 'cascade scale step'),
    'min_neighbors': Param(5, parse_positive_int, 'cascade neighbours for a detection'),
    'min_size': Param(24, parse_positive_int, 'smallest target (px)'),
    'max_task_len': Param(1000000, parse_positive_int, 'larger sort tasks get an error result'),
    'queue_size': Param(100, parse_positive_int, 'task subscriber queue length'),
    'max_image_pixels': Param(1 << 24, parse_positive_int, 'larger frames get an error result'),
    'window': Param(5.0, parse_positive, 'latency sample window (s)'),
    'publish_rate': Param(1.0, parse_positive, 'periodic selection flag rate (Hz)'),
    'update_rate': Param(10.0, parse_positive, 're-evaluation rate between samples (Hz)'),
    'hysteresis': Param(0.0, parse_non_negative, 'keep the current server while within this '
                        'of the best (s); 0: the paper'),
    'manager_timeout': Param(3.0, parse_positive, 'a flag older than this is stale: the robot '
                             'ranks its servers itself (s)'),
    'eject_time': Param(1.0, parse_positive, 'first ejection of a failing server (s); doubles '
                        'with each ejection in a row'),
    'eject_max': Param(30.0, parse_positive, 'longest ejection (s)'),
    'probation_probes': Param(2, parse_count, 'good probes before an ejected server takes a '
                              'task again'),
    'retry_factor': Param(5.0, parse_positive, "an attempt's deadline: this x the server's "
                          'recent p99 task round trip'),
    'retry_floor': Param(0.25, parse_positive, "shortest attempt deadline (s)"),
    'manager_node': Param('manager', parse_publisher, 'flags count only from this node '
                          '(*: from any)'),
    'robot_node': Param('robot{id}', parse_publisher, 'samples of robot {id} count only from '
                        'this node (*: from any)'),
    'master_check': Param(1.0, parse_positive, 'period of the check for a restarted roscore (s)'),
    'scenario': Param(REQUIRED, parse_text, 'scenario YAML file'),
    't0': Param(REQUIRED, parse_number, 'scenario time zero (epoch s)'),
    'duration': Param(30.0, parse_positive, 'how long to listen or measure (s)'),
    'output': Param('', parse_text, 'also write the result as JSON here'),
    'nodes': Param(REQUIRED, parse_names, 'node names to measure'),
    'delay': Param(5.0, parse_positive, 'wait this long before measuring (s)'),
    'area': Param(REQUIRED, parse_text, 'search area YAML file'),
    'radius': Param(150.0, parse_positive, 'a report this close to a target finds it (px)'),
    'timeout': Param(180.0, parse_positive, 'give up after this long (s)'),
}


def default(name):
    """The default of parameter ``name`` (KeyError for an unknown name)."""
    return PARAMS[name].default
