"""The settings a running robot takes (no rospy): what ``dynparam set`` may change, each
checked by its parameter's own parser and handed to the parts that read it.

A setting is live when every part that reads it reads it again at each use: the per-task
rule's answer window, the streams' rates, hedging, the retry budget, the probe rates
(within the probing chosen at start: uniform or adaptive) and the ejection times. The
others are read once, into structures built at start (a paper robot's sample window, the
routing, the task sizes...): they need a restart, and :func:`why_not_live` says so.
"""

import collections

from server_select.core.flow.task_flow import HEDGE_QUANTILE
from server_select.core.robot.refusals import not_for_setting

# name -> its type (what dynamic_reconfigure describes); the parameter's parser checks values
LIVE = collections.OrderedDict([
    ('window', float), ('task_rate', float), ('frame_rate', float), ('hedge', bool),
    ('retry_budget', float), ('probe_rate', float), ('contender_rate', float),
    ('background_rate', float), ('contender_budget', float), ('eject_time', float),
    ('eject_max', float),
])
# what docs/parameters.md says of them
LIVE_DOC = ('A robot takes %s while it runs, those that apply to it (`rosrun dynamic_reconfigure '
            'dynparam get /robot1` lists them). `dynparam set /robot1 window 3.0` checks the '
            'value as at start, puts it in force, logs the old and new value and writes it '
            'back; a value that cannot be taken is refused with the reason, and nothing of '
            'that call changes. The other settings are read once, at start. Not offered in a '
            'keyed fleet: its calls are not signed.')
STREAM_RATES = {'task_rate': 'sort', 'frame_rate': 'image'}   # setting -> its stream's kind


def why_not_live(name):
    """Why ``name`` cannot change while the robot runs (None: it can)."""
    if name in LIVE:
        return None
    return 'read once at start: restart the robot (roslaunch) to change ~%s' % name


def live_names(robot, get):
    """The live settings that apply to ``robot`` (its parameters read by ``get(name)``): a
    stream rate only if it has the stream, the window only for a rule that chooses per
    task, the probe rates of its probing, nothing its rule fixes."""
    kinds = set(s.kind.kind for s in robot.streams)
    plan, fixed = robot.plan, set(name for name, _ in not_for_setting(get))
    return [name for name in LIVE
            if name not in fixed and (name not in STREAM_RATES or STREAM_RATES[name] in kinds)
            and (name != 'window' or _rule_window(robot) is not None)
            and (name != 'probe_rate' or not plan.adaptive)
            and (name not in ('contender_rate', 'contender_budget') or plan.adaptive)]


def _not_here(name):
    """Why the live setting ``name`` does not apply to this robot."""
    if name in STREAM_RATES:
        return 'this robot sends no %s tasks' % STREAM_RATES[name]
    return {'window': 'a robot that follows its manager ranks by the manager\'s window: '
                      'tune ~window on the manager (a restart)',
            'probe_rate': 'this robot probes adaptively: tune ~contender_rate and '
                          '~background_rate'}.get(
        name, 'this robot probes every server alike: tune ~probe_rate')


def _rule_window(robot):
    balancer = robot.balancer
    return balancer if balancer is not None and hasattr(balancer, 'window') else None


class Tuning(object):
    """Settings changed on ``robot`` (a :class:`~server_select.core.robot.robot.Robot`);
    ``get(name)`` reads a setting's value in force at start."""

    def __init__(self, robot, get):
        self.robot = robot
        self.names = live_names(robot, get)
        self._fixed = dict(not_for_setting(get))
        self.values = dict((name, get(name)) for name in self.names)

    def set_all(self, wanted):
        """Put ``wanted`` {name: value (parsed already)} in force, all or none: ``[(name,
        old, new)]`` of those that changed; ValueError with the reason when one cannot."""
        for name in wanted:
            if name not in self.names:
                raise ValueError(why_not_live(name) or self._fixed.get(name) or _not_here(name))
        with self.robot._lock:
            changes = [(name, self.values[name], value)
                       for name, value in sorted(wanted.items()) if value != self.values[name]]
            self._check(dict(self.values, **wanted))
            for name, _old, value in changes:
                if name in STREAM_RATES:
                    self._rate(STREAM_RATES[name], value)
                else:
                    getattr(self, '_' + name)(value)
                self.values[name] = value
        return changes

    def set(self, name, value):
        """:meth:`set_all` of one setting: its old value."""
        old = self.values.get(name)
        self.set_all({name: value})
        return old

    def _check(self, values):
        health, plan = self.robot.health, self.robot.plan
        eject = values.get('eject_time', health.base), values.get('eject_max', health.longest)
        if eject[0] > eject[1]:
            raise ValueError('~eject_time %g would be longer than ~eject_max %g' % eject)
        if not plan.adaptive:
            return
        rates = (values.get('contender_rate', plan.contender_rate),
                 values.get('background_rate', plan.background_rate))
        if not rates[0] > 0:
            raise ValueError('~contender_rate 0 would turn adaptive probing off, which is '
                             'chosen at start: restart the robot to change it')
        if rates[0] < rates[1]:
            raise ValueError('~contender_rate %g would be below ~background_rate %g' % rates)

    # -- what each setting changes ---------------------------------------------------------
    def _window(self, seconds):
        robot = self.robot
        _rule_window(robot).window = seconds
        robot.plan.hold = seconds
        if robot.load is not None:      # (a ranking's robot: the estimates it keeps)
            robot.load.balancer.window = seconds

    def _rate(self, kind, rate):
        stream = self.robot.stream(kind)
        stream.set_rate(rate)
        if self.robot.load is not None:
            self.robot.load.set_rate(kind, rate)

    def _hedge(self, on):
        for stream in self.robot.streams:
            stream.flow.hedge = HEDGE_QUANTILE if on else None

    def _retry_budget(self, share):
        self.robot.budget.ratio = float(share)

    def _probe_rate(self, rate):
        self.robot.plan.tick = 1.0 / rate

    def _contender_rate(self, rate):
        plan = self.robot.plan
        plan.contender_rate, plan.tick = float(rate), 1.0 / rate

    def _background_rate(self, rate):
        self.robot.plan.background_rate = float(rate)

    def _contender_budget(self, rate):
        self.robot.plan.budget = float(rate)

    def _eject_time(self, seconds):
        self.robot.health.base = float(seconds)

    def _eject_max(self, seconds):
        self.robot.health.longest = float(seconds)
