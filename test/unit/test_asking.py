"""Asking is not deciding: for every rule (the fleet's and the league's peers), the health
table and the whole robot, 50 asks of where a task would go (and of what the robot's views
and probe plan ask) leave the object's whole state as it was and answer the same each
time. The move, and whatever a rule keeps about its choices, happen at the send. What a
rule keeps only to answer faster (its ``memos``) is left out, and shown to change no
answer."""

import collections
import random
import threading
import types

import pytest

from server_select.bench import decision_path
from server_select.core.load.work_queue import Load
from server_select.core.peers import balancers
from server_select.core.robot.health import ServerHealth
from test_least_latency import Clock

SERVERS = [1, 2, 3, 4]
ASKS = 50


def plain(value, seen=None):
    """``value``'s whole state as plain, comparable data (locks, threads and functions
    left out: they hold no state of the rule's)."""
    seen = set() if seen is None else seen
    if isinstance(value, random.Random):
        return ('Random', value.getstate())
    if isinstance(value, (types.FunctionType, types.MethodType, types.BuiltinFunctionType,
                          type(threading.Lock()), type(threading.RLock()), threading.Thread,
                          threading.Condition)):
        return None
    if isinstance(value, (int, float, str, bytes, bool, type(None))):
        return value
    if id(value) in seen:
        return ('seen', type(value).__name__)
    seen = seen | {id(value)}
    if isinstance(value, dict):
        return ('dict', sorted((repr(k), plain(v, seen)) for k, v in value.items()))
    if isinstance(value, (set, frozenset)):
        return ('set', sorted(repr(plain(v, seen)) for v in value))
    if isinstance(value, (list, tuple, collections.deque)):
        return (type(value).__name__, [plain(v, seen) for v in value])
    if hasattr(value, '__dict__') or hasattr(value, '__slots__'):
        fields = dict(vars(value)) if hasattr(value, '__dict__') else {}
        for memo in getattr(type(value), 'memos', ()):   # (proven transparent below)
            fields.pop(memo, None)
        for slot in getattr(type(value), '__slots__', ()):
            if hasattr(value, slot):
                fields[slot] = getattr(value, slot)
        return (type(value).__name__, plain(fields, seen))
    return repr(value)


def load(queued=0, workers=1, work=0.004):
    return Load(queued, 0, workers, 0.0, {'sort': work, 'image': 5 * work}, 0.2,
                {'sort': 0.0005, 'image': 0.001})


def fed(name, seed):
    """Rule ``name`` that has heard probes of every server and sent a few tasks."""
    clock = Clock()
    rule = balancers.make(name, rng=random.Random(seed), clock=clock, **(
        {'window': 2.0} if name == 'least_latency' else {}))
    for step in range(12):
        for server in SERVERS:
            rule.probed(server, 0.001 * server + 0.0002 * (step % 3), load(step % 4 == server))
        order = rule.order(SERVERS, 'sort')
        rule.started(order[0], 'sort', order=order)
        if step % 3:
            rule.ended(order[0], 0.005)
        clock.now += 0.1
    return rule, clock


def asks(rule):
    answers = []
    for i in range(ASKS):
        kind = ('sort', 'image', None)[i % 3]
        answer = [list(rule.order(SERVERS, kind)), sorted(rule.contenders(SERVERS)),
                  rule.task_rate()]
        if rule.own_view:
            answer += [rule.view(SERVERS), rule.choose(SERVERS, kind)]
        answers.append((kind, answer))
    return answers


@pytest.mark.parametrize('name', ('least_latency',) + balancers.PEERS)
@pytest.mark.parametrize('seed', [1, 2, 3])
def test_asking_a_rule_changes_nothing(name, seed):
    rule, _ = fed(name, seed)
    before = plain(rule)
    answers = asks(rule)
    assert plain(rule) == before
    for kind in ('sort', 'image', None):
        assert len(set(repr(a) for k, a in answers if k == kind)) == 1


class Forgetting(object):
    """``rule`` with its memos emptied before anything is asked of it."""

    def __init__(self, rule):
        self.rule = rule

    def __getattr__(self, name):
        estimates = self.rule.estimates
        for memo in estimates.memos:
            getattr(estimates, memo).clear()
        return getattr(self.rule, name)


def lived(rule, clock):
    """What ``rule`` answers over 12 s of probes, sends and answers leaving its window
    (levels enough for a wander)."""
    answers = []
    for step in range(120):
        clock.now += 0.1
        if step % 2 == 0:
            rule.probed(SERVERS[step % 3], 0.001 + 0.0003 * (step % 7), load(step % 2))
        if step % 6 == 0:
            rule.started(rule.order(SERVERS, 'sort')[0], 'sort')
        if step % 3 == 0:
            answers.append(asks(rule)[:3])
    assert any(rule.estimates.wander(s, 'sort') > 0 for s in SERVERS)
    return answers


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_a_rules_memos_change_no_answer(seed):
    """What a rule keeps to answer faster (its estimates' ``memos``, left out of the state
    compared above) gives the answers it would give without: asked with them emptied
    before every ask, a rule fed alike answers alike, while answers arrive and age out."""
    rule, clock = fed('least_latency', seed)
    memos = rule.estimates.memos
    assert memos
    kept = lived(rule, clock)
    assert all(getattr(rule.estimates, memo) for memo in memos)     # (they were used)
    twin, clock = fed('least_latency', seed)
    assert repr(lived(Forgetting(twin), clock)) == repr(kept)


@pytest.mark.parametrize('name', ('least_latency',) + balancers.PEERS)
def test_a_rule_changes_at_the_send(name):
    """The state asking leaves alone is what the send changes (so the test above is no
    test of a rule that keeps nothing)."""
    rule, _ = fed(name, 1)
    before = plain(rule)
    order = rule.order(SERVERS, 'sort')
    rule.started(order[0], 'sort', order=order)
    assert plain(rule) != before


def test_asking_the_health_table_changes_nothing():
    clock = Clock()
    health = ServerHealth(SERVERS, 1.0, 30.0, clock=clock)
    for server in SERVERS:
        health.probe_ok(server)
    health.failure(2, 'task timeout')
    health.busy(3, 1.0)
    health.started(4)
    before = plain(health)
    for ranking in ([1, 2, 3, 4], [], [2], [3, 1]) * (ASKS // 4):
        health.order(ranking)
        health.usable(ranking[0] if ranking else 1)
        health.panic(ranking)
    assert plain(health) == before
    assert health.order([]) == [4]       # the server the last task went to


def fleet_robot():
    """A fleet robot of 4 servers answering its probes, its sort tasks sent and answered
    (the one the decision-path benchmark traces)."""
    robot, clock, _ = decision_path.fleet_robot()
    return robot, clock


def test_asking_the_whole_robot_changes_nothing():
    robot, _ = fleet_robot()
    assert robot.streams[0].flow.sent > 0
    before = plain(robot)
    answers = set()
    for _ in range(ASKS):
        selection = robot.selection
        answers.add(repr((selection.candidates('sort'), selection.heading(), robot.ready(),
                          sorted(selection.contenders()), selection.task_rate(),
                          robot.next_probe_time(), robot.streams[0].next_time(),
                          selection.view())))
    assert plain(robot) == before
    assert len(answers) == 1
