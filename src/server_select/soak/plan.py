"""The soak's plan (no rospy): its fleet as a testbed scenario, and the nemesis schedule.

A :class:`Fault` is one fault of one kind at a planned scenario time: what it hits
(``target``), how long it lasts (``length``, s) and the recovery it is allowed once it ends
(``bound``, s). The schedule is drawn from a seeded random source: every kind ``repeats``
times, shuffled, one at a time, each after a calm stretch long enough for a pre-fault
reference. The short soak (make test) does every kind once in a few ``WAVES`` instead:
the faults of a wave start together, each on nodes of its own. Link outages are part of
the scenario the link emulator follows, so the nemesis only waits for them.
"""

import collections

Fault = collections.namedtuple('Fault', 'kind target at length bound')

SERVERS = (1, 2, 3, 4)
SERVER_SHARES = (0.55, 0.4, 0.3, 0.2)     # each server's share of one core: unequal
ROBOTS = (1, 2, 3, 4, 5, 6)
CAMERA_ROBOT = 6                          # the robot fed by a camera topic
BURST_ROBOTS = (101, 102, 103)   # the overload's extra robots, on the first robots' hosts
RECOVERY = 5.0            # s: the fleet is back this long after a fault ends
KEY_RECOVERY = 1.0        # s: after a key rotation (no node restarts)
ROSCORE_RECOVERY = 15.0   # s: after a roscore restart
# s from the nodes' registration (the scenario's time zero) to the first fault (windows
# full, first tasks answered): full, short
WARMUP = (45.0, 12.0)
TAIL = (20.0, 10.0)       # s after the last fault's allowed recovery: full, short

# Fault kinds and their length (s) in a full soak and in the short one (make test).
KINDS = collections.OrderedDict([
    ('server_kill', (3.0, 2.0)),      # SIGKILL, restarted under the same name after this
    ('server_stop', (5.0, 5.0)),      # SIGSTOP, SIGCONT after this
    ('link_down', (10.0, 6.0)),       # every link of a server down
    ('manager_kill', (3.0, 2.0)),     # SIGKILL, restarted after this
    ('roscore_kill', (5.0, 3.0)),     # roscore's processes SIGKILLed, restarted after this
    ('robot_kill', (3.0, 2.0)),       # SIGKILL, restarted after this
    ('overload', (30.0, 12.0)),       # the burst robots double the offered load
    ('intruder', (20.0, 10.0)),       # a keyless node publishes tasks and forged flags
    ('key_rotation', (0.0, 0.0)),     # every node told to read its keys again (as long as it takes)
])


# The short soak's waves: faults on different nodes at once (each wave's server faults on
# servers of their own); a master restart and a key rotation, which every node lives
# through, each alone.
WAVES = (('server_kill', 'server_stop', 'link_down', 'robot_kill', 'manager_kill', 'overload',
          'intruder'), ('roscore_kill',), ('key_rotation',))
SERVER_FAULTS = ('server_kill', 'server_stop', 'link_down')


def target_of(kind, rng, servers=SERVERS):
    """What a fault of ``kind`` hits: a server (of ``servers``) or robot id, or None (the
    fleet)."""
    if kind in SERVER_FAULTS:
        return rng.choice(servers)
    if kind == 'robot_kill':
        return rng.choice(ROBOTS)
    return None


def _timing(short):
    """(length of each kind, calm s before each fault, s planned for a key rotation)."""
    lengths = dict((kind, pair[1 if short else 0]) for kind, pair in KINDS.items())
    return lengths, (4.0 if short else 45.0), (3.0 if short else 10.0)


def _slot(kind, short):
    """Planned s of one fault of ``kind``: calm before, its length, its recovery bound."""
    lengths, calm, rotation = _timing(short)
    return calm + (lengths[kind] or rotation) + bound_of(kind)


def bound_of(kind):
    return {'roscore_kill': ROSCORE_RECOVERY, 'key_rotation': KEY_RECOVERY}.get(kind, RECOVERY)


def _waves(kinds):
    """The short soak's waves of ``kinds`` (those of no wave: a wave each), none empty."""
    waves = [tuple(k for k in wave if k in kinds) for wave in WAVES]
    waves += [(kind,) for kind in kinds if not any(kind in wave for wave in WAVES)]
    return [wave for wave in waves if wave]


def _wave_slot(wave, short):
    lengths, calm, rotation = _timing(short)
    return calm + max(lengths[k] or rotation for k in wave) + max(bound_of(k) for k in wave)


def needed(repeats, short=False, kinds=tuple(KINDS)):
    """Scenario s a soak with ``repeats`` faults of each of ``kinds`` needs at least (the
    short one: one of each, in waves)."""
    if short:
        return WARMUP[1] + TAIL[1] + sum(_wave_slot(w, True) for w in _waves(kinds))
    return WARMUP[short] + TAIL[short] + repeats * sum(_slot(kind, short) for kind in kinds)


def schedule(duration, rng, repeats=None, short=False, kinds=tuple(KINDS)):
    """The faults of a soak of ``duration`` s, in time order. ``repeats``: faults of each
    of ``kinds`` (None: as many as fit, at least 2); ``short``: one of each, in waves, with
    the short lengths and calm stretches. Raises ValueError when they do not fit, or for a
    kind not in KINDS."""
    unknown = sorted(set(kinds) - set(KINDS))
    if unknown:
        raise ValueError('no fault kind %s (the kinds: %s)'
                         % (', '.join(unknown), ', '.join(KINDS)))
    if short:
        return _in_waves(duration, rng, kinds)
    lengths, calm, rotation = _timing(short)
    one_round = sum(_slot(kind, short) for kind in kinds)
    room = duration - WARMUP[short] - TAIL[short]
    if repeats is None:
        repeats = max(2, int(room // one_round))
    if repeats * one_round > room:
        raise ValueError('%d faults of each kind need a soak of %.0f s at least, not %.0f s'
                         % (repeats, needed(repeats, short, kinds), duration))
    order = [kind for kind in kinds for _ in range(repeats)]
    rng.shuffle(order)
    spare = (room - repeats * one_round) / len(order)
    faults, at = [], WARMUP[short]
    for kind in order:
        at += calm + spare
        faults.append(Fault(kind, target_of(kind, rng), round(at, 1), lengths[kind],
                            bound_of(kind)))
        at += (lengths[kind] or rotation) + bound_of(kind)
    return faults


def _in_waves(duration, rng, kinds):
    """The short soak: every kind of ``kinds`` once, the faults of a wave at one time."""
    if needed(1, True, kinds) > duration:
        raise ValueError('a short soak of %s needs %.0f s at least, not %.0f s'
                         % (', '.join(kinds), needed(1, True, kinds), duration))
    lengths, calm, _ = _timing(True)
    faults, at = [], WARMUP[1]
    for wave in _waves(kinds):
        servers = rng.sample(SERVERS, sum(1 for k in wave if k in SERVER_FAULTS))
        for kind in wave:
            target = servers.pop() if kind in SERVER_FAULTS else target_of(kind, rng)
            faults.append(Fault(kind, target, at + calm, lengths[kind], bound_of(kind)))
        at += _wave_slot(wave, True)
    return faults


def scenario(faults, duration, name='soak'):
    """The testbed scenario of a soak: the manager, 4 servers of unequal CPU shares, 6
    robots; links of 1-4 ms one way, and each ``link_down`` fault cutting every link of
    its server for its length."""
    hosts = {'manager': {'role': 'manager'}}
    for server, share in zip(SERVERS, SERVER_SHARES):
        hosts['server%d' % server] = {'role': 'server', 'id': server, 'cpu': share}
    for robot in ROBOTS:
        hosts['robot%d' % robot] = {'role': 'robot', 'id': robot}
    links = {}
    for robot in ROBOTS:
        for server in SERVERS:
            delay = 1.0 + (robot + server) % 4
            links['robot%d server%d' % (robot, server)] = [
                {'at': 0, 'delay': delay, 'jitter': delay / 10.0}]
    for fault in (f for f in faults if f.kind == 'link_down'):
        server = 'server%d' % fault.target
        for other in (h for h in hosts if h != server):
            pair = ' '.join(sorted((other, server)))
            events = links.setdefault(pair, [{'at': 0, 'delay': 0.5, 'jitter': 0.05}])
            events.append({'at': fault.at, 'down': True})
            events.append({'at': fault.at + fault.length, 'down': False})
    return {'name': name, 'duration': duration, 'time_zero': 'ready', 'hosts': hosts,
            'default': {'delay': 0.5, 'jitter': 0.05}, 'links': links}


class KeyRing(object):
    """The fleet's keys through a soak: every node signs with one and also admits one
    (``fleet_key``, ``fleet_key_next``). A rotation tells every node to read them again,
    in passes: each pass's new state must admit what nodes not yet told sign, and the
    reverse."""

    def __init__(self, paths):
        self.paths = list(paths)
        self.index, self.accepts_previous = 0, False     # signs paths[0], accepts paths[1]

    def state(self):
        """(key signed with, key also accepted)."""
        other = self.index - 1 if self.accepts_previous else self.index + 1
        return self.paths[self.index], self.paths[other]

    def passes(self):
        """The passes of the next rotation, each a function moving to its state: hand every
        node the next key as the one also accepted (unless it has it), then sign with it."""
        def hand_out():
            self.accepts_previous = False

        def switch():
            self.index += 1
            self.accepts_previous = True
        return [switch] if not self.accepts_previous else [hand_out, switch]
