"""Task types: a request/result message pair and one class (see :class:`TaskPlugin`).

The built-in sort and image tasks are task types like any other
(:mod:`server_select.tasks`); more are added without editing the nodes, named
``module:Class`` in the robot's and the server's ``~task_plugins``. A robot sends every
type's tasks through a :class:`~server_select.core.flow.task_flow.TaskFlow` (selection, failover,
one ``task_report`` each); a server answers every type through a :class:`PluginHandler`. A
plug-in's own settings are the private parameters under its kind (``~orb/rate``,
``~orb/source``, ...).
"""

import importlib
import threading
import time

import rospy

from server_select.core.config.params import ParamError
from server_select.ros.graph import publisher_of
from server_select.ros import params_in_force, seal
from server_select.ros.endpoints import ServerEndpoint


class TaskPlugin(object):
    """What a task type provides. The request message has ``header``, ``robot_id``,
    ``task_id`` and ``server_id`` (and ``float64 budget``, for servers to refuse what
    they cannot do in time); the result message copies them and adds ``ok``, ``error``
    and ``process_time`` (and ``bool busy``); the rest is the plug-in's.

    Robot side (``robot_id`` is an int): ``make``, ``check``, ``run_local``, ``rate`` and
    ``ready``. Server side (``robot_id`` is None): ``start``, ``warm``, ``handle`` and
    ``rehearse``.
    """

    kind = None                          # the name in task reports and of the settings
    input = 'its input'                  # what ready() waits for (for the log)
    # True: only the newest task is worth anything (a camera frame): a late one is not
    # sent again while a newer one waits
    newest_wins = False
    task_type = result_type = None       # the message classes
    task_topic = result_topic = None     # fleet-level topic names

    def __init__(self, robot_id, settings):
        self.robot_id, self.settings = robot_id, settings

    @property
    def rate(self):
        """Tasks per second a robot sends (setting ``rate``, default 1)."""
        return float(self.settings.get('rate', 1.0))

    def ready(self):
        """Whether there is input for a task now (False: none is made this time)."""
        return True

    def warm(self):
        """Server side: load what handling a task needs (a library, a model), once, on a
        thread of its own, when a robot's probe first says it sends this kind: the first
        task is then not the one that waits for it (nothing here)."""

    def make(self, task_id, stamp):
        """``(request, context)``; raise ValueError when no task can be made now."""
        raise NotImplementedError

    def check(self, result, context):
        """Why an ``ok`` result is wrong, or None."""
        return None

    def run_local(self, task_id, stamp):
        """Do the work in the robot (mode ``local``); an error string or None."""
        raise NotImplementedError

    def start(self):
        """Server side: make what :meth:`handle` publishes besides the result (if anything)."""

    def handle(self, task, result):
        """Fill ``result`` for ``task`` on a server; raise ValueError to reject the task."""
        raise NotImplementedError

    def rehearse(self, task, result):
        """Server side: ``task``'s work again, into ``result`` and nowhere else: what a
        server nobody sends to times to say what one takes now (``~check_every``). False,
        the default: not rehearsed (a type's ``handle`` may act beyond its result)."""
        return False

    def max_bytes(self):
        """Server side: the longest task message taken, bytes (setting ``max_bytes``,
        default 4 MiB); a longer one is refused from its length, unread
        (:mod:`server_select.ros.bounded_read`)."""
        return int(self.settings.get('max_bytes', 4 << 20))

    def held_bytes(self, task):
        """Server side: about how much memory ``task`` holds while queued (what the queue's
        ``~max_queue_bytes`` counts; :func:`held_bytes`)."""
        return held_bytes(task)


MESSAGE_SLACK = 4096   # a task message's bytes besides its payload: header, ids, names
PER_NUMBER = 36     # bytes of one deserialized number of an array: its object and pointer


def held_bytes(msg):
    """About the memory a deserialized message holds: its strings' and byte arrays'
    lengths, ``PER_NUMBER`` for each number of an array (genpy reads ``int32[]`` into a
    tuple of Python ints), nested messages alike. A ROS array holds one type, so an array
    whose first item is no message is counted by its length (looking at each of 100,000
    numbers took a sixth of a flooded server's CPU, on its receiving threads)."""
    total = 0
    for name in getattr(msg, '__slots__', ()):
        value = getattr(msg, name, None)
        if isinstance(value, (bytes, str, bytearray)):
            total += len(value)
        elif isinstance(value, (list, tuple)):
            if value and hasattr(value[0], '__slots__'):
                total += sum(held_bytes(item) for item in value)
            else:
                total += PER_NUMBER * len(value)
        elif hasattr(value, '__slots__'):
            total += held_bytes(value)
    return total


def load(spec, robot_id, name='~task_plugins'):
    """An instance of the plug-in ``module:Class``, with its settings (ParamError if not)."""
    module_name, _, class_name = spec.partition(':')
    try:
        cls = getattr(importlib.import_module(module_name), class_name)
    except (ImportError, AttributeError, ValueError) as error:
        raise ParamError('%s: cannot load %r (module:Class): %s' % (name, spec, error))
    if not (isinstance(cls, type) and issubclass(cls, TaskPlugin)):
        raise ParamError('%s: %r is not a TaskPlugin' % (name, spec))
    seal.require_sealable(cls.result_type, "the result of task type '%s'" % cls.kind)
    params_in_force.reads_namespace(cls.kind)
    settings = rospy.get_param('~' + cls.kind, {})
    if not isinstance(settings, dict):
        raise ParamError('~%s: expected a mapping of settings, got %r' % (cls.kind, settings))
    try:
        return cls(robot_id, settings)
    except (ValueError, OSError) as error:
        raise ParamError('~%s: %s' % (cls.kind, error))


class PluginHandler(object):
    """A server's side of one task type: ``on_task`` makes the result of a task addressed
    here (an error result when the task type rejects it), after which ``work()`` runs (the
    server's ``~work_delay``); the endpoint hands its tasks to ``submit`` (the server's
    workers)."""

    def __init__(self, server_id, plugin, submit, queue_size=100, direct=False, work=None):
        self.server_id, self.plugin = server_id, plugin
        self.endpoint = ServerEndpoint(server_id, plugin, self.on_task, direct, submit,
                                       queue_size, rehearse=self.rehearse)
        self.work = work
        self._lock = threading.Lock()
        self.done = self.rejected = 0

    def start(self):
        self.plugin.start()
        self.endpoint.start()

    def _result(self, task):
        return self.plugin.result_type(header=task.header, robot_id=task.robot_id,
                                       task_id=task.task_id, server_id=self.server_id)

    def rehearse(self, task):
        """``task``'s work again with no effect beyond its result, which goes nowhere (a
        check: :meth:`TaskPlugin.rehearse`); False when its type does not rehearse."""
        if self.plugin.rehearse(task, self._result(task)) is False:
            return False
        if self.work is not None:
            self.work()
        return True

    def on_task(self, task):
        """The result of ``task``."""
        result = self._result(task)
        start = time.perf_counter()
        try:
            self.plugin.handle(task, result)
            result.ok = True
        except ValueError as error:
            result = self.endpoint.error_result(task, str(error))
            rospy.logerr_throttle(1.0, 'server %d: %s task %d of robot %d (from %s) rejected: '
                                  '%s' % (self.server_id, self.plugin.kind, task.task_id,
                                          task.robot_id, publisher_of(task), error))
        else:
            if self.work is not None:
                self.work()
        result.process_time = time.perf_counter() - start
        with self._lock:
            self.done += result.ok
            self.rejected += not result.ok
        return result
