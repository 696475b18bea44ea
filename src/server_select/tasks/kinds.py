"""The task types a node's parameters ask for: the built-in sort and image task types
(:mod:`server_select.tasks.sort`, :mod:`server_select.tasks.image`) and the plug-ins of
``~task_plugins``: each a :class:`~server_select.ros.plugins.TaskPlugin`.

The built-in types take their settings from the node's own parameters (``~task_size``,
``~image_source``, ``~max_task_len``, ...), a plug-in from those under its kind
(``~orb/...``). A request names no server: the robot stamps ``server_id`` on each attempt
(a task may be sent again elsewhere).
"""

from server_select.core.config.params import ParamError
from server_select.ros.camera import TopicSource
from server_select.ros.plugins import load as load_plugin
from server_select.ros.search import SearchParticipant
from server_select.tasks.image import Frames
from server_select.tasks.sort import Sort
from server_select.vision.detection import DetectorError, make_detector
from server_select.vision.image_source import SourceError, open_source
from server_select.vision.search import SearchError


def _detectors(param, count, load=True):
    try:
        return [make_detector(param, load) for _ in range(count)]
    except DetectorError as error:
        raise ParamError('~detector/~cascade: %s' % error)


def image_kind(robot_id, mode, param):
    """The camera stream the parameters describe (``param(name)`` reads one): a topic
    (``~image_topic``) or a source (``~image_source``); ParamError when they are wrong."""
    if param('image_source') and param('image_topic'):
        raise ParamError('~image_source and ~image_topic: set one of them, not both')
    if param('image_topic'):
        source = TopicSource(param('image_topic'), param('max_image_pixels'))
    else:
        try:
            source = open_source(param('image_source'), param('robot_index'),
                                 param('robot_count'), param('speed'))
        except (SourceError, SearchError, OSError) as error:
            raise ParamError('~image_source: %s' % error)
    search = SearchParticipant(robot_id, param('merge_radius'), getattr(source, 'world', None))
    return Frames(robot_id, {
        'encoding': param('image_encoding'), 'transport': param('image_transport'),
        'quality': param('jpeg_quality'), 'max_pixels': param('max_image_pixels'),
        'start': param('sweep_start'),
        'input': param('image_topic') or param('image_source')}, source=source, search=search,
        detectors=_detectors(param, 1) if mode == 'local' else ())


def stream_kinds(robot_id, mode, param):
    """``[(task type, rate)]`` of each stream a robot's parameters ask for; ParamError when
    they ask for none or are wrong."""
    kinds = []
    if param('sort_tasks'):
        kinds.append((Sort(robot_id, {'size': param('task_size'),
                                      'seed': param('seed', default=robot_id)}),
                      param('task_rate')))
    if param('image_source') or param('image_topic'):
        kinds.append((image_kind(robot_id, mode, param), param('frame_rate')))
    kinds += [(plugin, plugin.rate) for plugin in
              (load_plugin(spec, robot_id) for spec in param('task_plugins'))]
    if not kinds:
        raise ParamError('~sort_tasks is false, and neither ~image_source, ~image_topic '
                         'nor ~task_plugins is set: no tasks to send')
    return kinds


def server_kinds(param, workers):
    """Every task type a server's parameters ask for: sort, image (with a detector for
    each of ``workers``, checked now, OpenCV loaded once a robot says it sends frames)
    and the plug-ins; ParamError when they are wrong."""
    return [Sort(None, {'max_len': param('max_task_len')}),
            Frames(None, {'quality': param('jpeg_quality'),
                          'max_pixels': param('max_image_pixels')},
                   detectors=_detectors(param, workers, load=False))] + \
        [load_plugin(spec, None) for spec in param('task_plugins')]
