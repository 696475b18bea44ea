"""Testbed scenarios: hosts and time-varying per-pair link conditions (no rospy).

A scenario is a YAML mapping (a host may also start late, hang, get slower, have a CPU
share, a memory limit or work of its own: docs/evaluation.md has every key)::

    name: paper_moving_robots
    duration: 120               # seconds the experiment runs
    time_zero: launch           # or ready: time starts once the nodes started at 0 are up
    hosts:                      # every host of the topology
      manager: {role: manager}
      server1: {role: server, id: 1}
      robot1:  {role: robot, id: 1}
    default: {delay: 1.0}       # link state of pairs not listed: one-way delay in ms, ...
    links:                      # per unordered pair of hosts "a b", events in time order
      robot1 server1:
        - {at: 0, delay: 2}                 # step to 2 ms one way (both directions)
        - {at: 30, ramp: 20, over: 40}      # linear from the value at t=30 to 20 ms at t=70
        - {at: 80, down: true}              # every packet dropped
        - {at: 90, delay: 5, jitter: 0.5, loss: 0.01}   # up again

An event may set ``delay`` (ms, a step), ``ramp`` + ``over`` (ms, s: linear), ``jitter``
(ms, uniform), ``loss`` (0..1), ``down`` and ``rate`` (MB/s each way, 0: unlimited); what
it does not set carries over. Delays are one way: a round trip takes twice the delay.
"""

import bisect
import collections

import yaml

from server_select.core.config.params import nearest
from server_select.core.ranking.rank import NO_SERVER
from server_select.testbed.fields import (DEFAULT_CPU_PERIOD_MS, ScenarioError,  # noqa: F401
                                          hang_times, number as _number, resources,
                                          work_times)

ROLES = ('manager', 'server', 'robot')

LinkState = collections.namedtuple('LinkState', 'delay jitter loss down rate')
LinkState.__new__.__defaults__ = (0.0,)   # rate: MB/s each way, 0 = unlimited
Host = collections.namedtuple('Host', 'name role id start stop hang work cpu cpu_period '
                              'memory busy')
# hang: [(from, to)] s; work: [(at s, delay s)]; cpu: share of one core, None: no limit;
# cpu_period: ms; memory: MiB, None: no limit; busy: share of the host's CPU its own work uses
Host.__new__.__defaults__ = ((), (), None, DEFAULT_CPU_PERIOD_MS, None, 0.0)


def pair_key(a, b):
    return (a, b) if a <= b else (b, a)


class LinkProfile(object):
    """The state of one link over time, built from its event list."""

    def __init__(self, events, default, where='link'):
        self.where = where
        self.times, self.states, self.ramps = [], [], []
        state = default
        last_at = None
        for index, event in enumerate(events or []):
            here = '%s event %d' % (where, index + 1)
            if not isinstance(event, dict) or 'at' not in event:
                raise ScenarioError('%s: expected a mapping with "at", got %r' % (here, event))
            unknown = set(event) - {'at', 'delay', 'ramp', 'over', 'jitter', 'loss', 'down',
                                    'rate'}
            if unknown:
                raise ScenarioError('%s: unknown keys %s' % (here, sorted(unknown)))
            at = _number(event['at'], here + ' at', minimum=0.0)
            if last_at is not None and at < last_at:
                raise ScenarioError('%s: events must be in time order (%g after %g)'
                                    % (here, at, last_at))
            last_at = at
            if 'delay' in event and 'ramp' in event:
                raise ScenarioError('%s: give either delay or ramp, not both' % here)
            start = self.value_at(at) if self.times else state
            delay = start.delay
            ramp = None
            if 'delay' in event:
                delay = _number(event['delay'], here + ' delay', minimum=0.0)
            if 'ramp' in event:
                if 'over' not in event:
                    raise ScenarioError('%s: ramp needs "over" (seconds)' % here)
                target = _number(event['ramp'], here + ' ramp', minimum=0.0)
                over = _number(event['over'], here + ' over', minimum=0.0)
                if over > 0:
                    ramp = (at, at + over, start.delay, target)
                delay = start.delay if ramp else target
            elif 'over' in event:
                raise ScenarioError('%s: "over" without "ramp"' % here)
            jitter = _number(event.get('jitter', start.jitter), here + ' jitter', minimum=0.0)
            loss = _number(event.get('loss', start.loss), here + ' loss', minimum=0.0, maximum=1.0)
            down = event.get('down', start.down)
            if not isinstance(down, bool):
                raise ScenarioError('%s: down must be true or false, got %r' % (here, down))
            self.times.append(at)
            rate = _number(event.get('rate', start.rate), here + ' rate', minimum=0.0)
            self.states.append(LinkState(delay, jitter, loss, down, rate))
            self.ramps.append(ramp)
        self.default = state

    def value_at(self, t):
        """LinkState at scenario time ``t`` (seconds)."""
        index = bisect.bisect_right(self.times, t) - 1
        if index < 0:
            return self.default
        state, ramp = self.states[index], self.ramps[index]
        if ramp is not None:
            t0, t1, d0, d1 = ramp
            fraction = 1.0 if t >= t1 else (t - t0) / (t1 - t0)
            state = state._replace(delay=d0 + (d1 - d0) * fraction)
        return state


TOP_KEYS = ('name', 'duration', 'time_zero', 'hosts', 'default', 'links', 'suite')


def _nearest(key):
    near = nearest(key, TOP_KEYS)
    return 'did you mean %s?' % near if near else '%s is not one of %s' % (key, ', '.join(
        TOP_KEYS))


class Scenario(object):
    """Hosts and link profiles of one testbed run."""

    def __init__(self, data, source='scenario'):
        if not isinstance(data, dict):
            raise ScenarioError('%s: expected a mapping at top level' % source)
        unknown = sorted(set(map(str, data)) - set(TOP_KEYS))
        if unknown:
            raise ScenarioError('unknown keys at top level %s (%s)' % (
                unknown, '; '.join(_nearest(key) for key in unknown)))
        self.source = source
        self.name = str(data.get('name', 'scenario'))
        self.duration = _number(data.get('duration', 60), 'duration', minimum=1.0)
        self.time_zero = str(data.get('time_zero', 'launch'))   # or ready: see the example
        if self.time_zero not in ('launch', 'ready'):
            raise ScenarioError('time_zero: %r is neither launch nor ready' % self.time_zero)
        self.hosts = self._hosts(data.get('hosts'))
        # suite: what the suite and the simulator run on it (robot_args, variants, ...)
        self.suite, default = data.get('suite') or {}, data.get('default') or {}
        for key, value in (('suite', self.suite), ('default', default)):
            if not isinstance(value, dict):
                raise ScenarioError('%s: expected a mapping' % key)
        self.default_state = base = LinkProfile(
            [dict(default, at=0)], LinkState(0.0, 0.0, 0.0, False), 'default').value_at(0)
        self.links = {}
        for key, events in (data.get('links') or {}).items():
            names = str(key).replace(',', ' ').replace('-', ' ').split()
            if len(names) != 2 or names[0] == names[1]:
                raise ScenarioError('links: "%s" is not a pair of two hosts' % key)
            for name in names:
                if name not in self.hosts:
                    raise ScenarioError('links: "%s" names unknown host %s' % (key, name))
            pair = pair_key(*names)
            if pair in self.links:
                raise ScenarioError('links: pair %s %s given twice' % pair)
            self.links[pair] = LinkProfile(events, base, 'links "%s"' % key)

    @classmethod
    def load(cls, path):
        try:
            with open(path) as stream:
                data = yaml.safe_load(stream)
        except (OSError, yaml.YAMLError) as error:
            raise ScenarioError('%s: %s' % (path, error))
        try:
            return cls(data, path)
        except ScenarioError as error:     # the file's name first, once
            text = str(error)
            raise ScenarioError(text if text.startswith(str(path)) else
                                '%s: %s' % (path, text))

    def _hosts(self, hosts):
        if not isinstance(hosts, dict) or not hosts:
            raise ScenarioError('hosts: expected a non-empty mapping of host names')
        result = collections.OrderedDict()
        ids = set()
        for name, spec in hosts.items():
            name = str(name)
            if not name.replace('_', '').isalnum() or len(name) > 10:
                raise ScenarioError('hosts: name %r must be alphanumeric, at most 10 chars' % name)
            spec = spec or {}
            role = spec.get('role')
            if role not in ROLES:
                raise ScenarioError('hosts: %s has role %r, expected one of %s'
                                    % (name, role, ', '.join(ROLES)))
            ident = spec.get('id')
            if role != 'manager':
                if not isinstance(ident, int) or isinstance(ident, bool) or ident < 0:
                    raise ScenarioError('hosts: %s needs a non-negative integer id' % name)
                if (role, ident) in ids:
                    raise ScenarioError('hosts: two %ss with id %d' % (role, ident))
                ids.add((role, ident))
            start = _number(spec.get('start', 0.0), 'hosts: %s start' % name, 0.0)
            stop = spec.get('stop')
            if stop is not None:
                stop = _number(stop, 'hosts: %s stop' % name, start)
            if role == 'manager' and (start or stop is not None):
                raise ScenarioError('hosts: the manager runs for the whole scenario')
            hang, work = hang_times(spec.get('hang'), name), work_times(spec.get('work'), name)
            if role != 'server' and (hang or work):
                raise ScenarioError('hosts: only a server may hang or get work (%s)' % name)
            result[name] = Host(name, role, ident, start, stop, hang, work,
                                *resources(name, role, spec))
        if sum(1 for h in result.values() if h.role == 'manager') != 1:
            raise ScenarioError('hosts: exactly one host must have role manager')
        return result

    def of_role(self, role):
        return [h for h in self.hosts.values() if h.role == role]

    @property
    def manager(self):
        return self.of_role('manager')[0]

    def host_for(self, role, ident):
        for host in (h for h in self.hosts.values() if h.role == role and h.id == ident):
            return host
        raise KeyError('%s %s' % (role, ident))

    def link(self, a, b, t):
        """LinkState between hosts ``a`` and ``b`` at scenario time ``t``."""
        profile = self.links.get(pair_key(a, b))
        return profile.value_at(t) if profile else self.default_state

    def ranking(self, robot_id, t):
        """The robot's servers whose links are up at ``t``, best first, and those down (or
        not running: a host's ``start`` / ``stop`` times, or hung). A server's ``work`` (each
        task takes that much longer) counts as half of it each way: the oracle knows what a
        task there takes beyond the servers' common work, not only the network.

        Returns ``([(one-way delay ms, server id), ...], [down server ids])``: lowest delay
        first, ties to the lower server id (the choice of an oracle that knows the scenario).
        """
        robot = self.host_for('robot', robot_id)
        up, down = [], []
        for server in sorted(self.of_role('server'), key=lambda h: h.id):
            state = self.link(robot.name, server.name, t)
            running = server.start <= t and (server.stop is None or t < server.stop) and \
                not any(a <= t < b for a, b in server.hang)
            extra = [delay for at, delay in server.work if at <= t]
            delay = state.delay + (500.0 * extra[-1] if extra else 0.0)
            (down if state.down or not running else up).append((delay, server.id))
        return sorted(up, key=lambda pair: pair[0]), [s for _, s in down]

    def nearest_server(self, robot_id, t):
        """The truly nearest server of a robot at ``t`` (NO_SERVER if every link is down)."""
        ranked, _ = self.ranking(robot_id, t)
        return ranked[0][1] if ranked else NO_SERVER
