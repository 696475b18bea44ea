"""The simulator's parts: the event loop and random streams, links to the millisecond,
the server, the statistics, the generator, and whole runs (same seed, same figures)."""

import random

import pytest

from server_select.sim import generate, report, stats
from server_select.sim.events import EventLoop, Streams, Wakeup
from server_select.sim.figures import figures
from server_select.sim.model import Model
from server_select.sim.network import Network
from server_select.sim.run import measured_window, simulate, variant
from server_select.sim.server import SimServer
from server_select.sim.tasks import Task
from server_select.testbed.scenario import Scenario


def scenario(links, servers=None, duration=60.0, args=None):
    hosts = {'manager': {'role': 'manager'}, 'robot1': {'role': 'robot', 'id': 1}}
    for ident, spec in (servers or {1: {}}).items():
        hosts['server%d' % ident] = dict(spec, role='server', id=ident)
    return Scenario({'name': 't', 'duration': duration, 'hosts': hosts, 'links': links,
                     'default': {'delay': 10}, 'suite': {'robot_args': args or {}}})


def test_events_run_in_time_order_and_ties_in_the_order_scheduled():
    loop, seen = EventLoop(), []
    for when, tag in ((2.0, 'c'), (1.0, 'a'), (1.0, 'b')):
        loop.at(when, seen.append, tag)
    loop.run(1.5)
    assert seen == ['a', 'b'] and loop.now() == 1.5
    loop.run(10.0)
    assert seen == ['a', 'b', 'c']


def test_a_wakeup_fires_once_at_the_earliest_time_asked():
    loop, fired = EventLoop(), []
    wake = Wakeup(loop, lambda: fired.append(loop.now()))
    wake.request(5.0)
    wake.request(3.0)
    wake.request(4.0)           # later than the pending one: nothing
    loop.run(10.0)
    assert fired == [3.0]


def test_streams_are_named_by_purpose_and_repeat_with_the_seed():
    a, b = Streams(7), Streams(7)
    first = [a.rng('link', 'x').random() for _ in range(3)]
    a.rng('other').random()     # a draw elsewhere does not shift this stream
    assert [b.rng('link', 'x').random() for _ in range(3)] == first
    assert Streams(8).rng('link', 'x').random() != first[0]


def test_a_message_takes_the_links_delay_at_its_time_plus_the_middleware_to_the_ms():
    sc = scenario({'robot1 server1': [{'at': 0, 'delay': 2}, {'at': 10, 'ramp': 12, 'over': 10}]})
    network = Network(sc, Streams(1), hop=0.001)
    assert network.once('robot1', 'server1', 5.0, 100, 'p') == pytest.approx(5.003)
    assert network.once('robot1', 'server1', 15.0, 100, 'p') == pytest.approx(15.008)
    assert network.once('server1', 'robot1', 25.0, 100, 'p') == pytest.approx(25.013)


def test_a_message_sent_into_an_outage_arrives_at_the_first_retry_after_it():
    """Retransmissions at 0.2, 0.6, 1.4, 3.0, 6.2, 12.6 s after the send (Linux's RTO from
    200 ms, doubling): sent at 10.05 into an outage until 18, it arrives at 22.65 + 2 ms."""
    sc = scenario({'robot1 server1': [{'at': 0, 'delay': 2}, {'at': 10, 'down': True},
                                      {'at': 18, 'down': False}]})
    connection = Network(sc, Streams(1), hop=0.0).connection('robot1', 'server1', 'task')
    assert connection.send(10.05, 4000) == pytest.approx(22.652)
    # what is written behind it goes with it; the connection is stalled meanwhile
    assert connection.send(19.0, 4000) == pytest.approx(22.652)
    assert not connection.stalled(10.5) and connection.stalled(19.0)
    assert not connection.stalled(23.0)


def test_in_order_delivery_under_jitter():
    sc = scenario({'robot1 server1': [{'at': 0, 'delay': 5, 'jitter': 4}]})
    connection = Network(sc, Streams(3), hop=0.0).connection('robot1', 'server1', 'task')
    arrivals = [connection.send(t * 0.001, 100) for t in range(200)]
    assert arrivals == sorted(arrivals)


class _Model(object):
    probe_cpu, cpu_factor, warm = 0.0005, 1.0, {}


def _server(spec, loop):
    host = Scenario({'hosts': {'manager': {'role': 'manager'},
                               's': dict(spec, role='server', id=1)}}).hosts['s']
    return SimServer(loop, host, _Model(), Streams(1))


def test_a_server_refuses_at_once_what_it_cannot_finish_by_its_deadline():
    """Once it has timed a task of the kind (its first is not timed): 0.2 s each at half
    a core (its quota given per 1 ms: as even as a slower core), so with a 0.5 s budget the
    third of three sent together is refused at once."""
    loop, answers = EventLoop(), []
    server = _server({'cpu': 0.5, 'cpu_period': 1.0}, loop)

    def reply(task, ok, error, busy):
        answers.append((task.task_id, loop.now(), busy))
    for n in range(2):
        server.submit(Task(1, n, 'sort', 0.1, 100, 0.1), 0.0, reply)   # no deadline: learnt
    loop.run(0.9)
    for n in range(2, 5):
        loop.at(1.0, server.submit, Task(1, n, 'sort', 0.1, 100, 0.1), 0.5, reply)
    loop.run(5.0)
    assert [(n, round(t, 2), busy) for n, t, busy in answers] == [
        (0, 0.2, False), (1, 0.4, False), (4, 1.0, True), (2, 1.2, False), (3, 1.4, False)]


def test_a_hung_server_works_and_answers_after_it_goes_on_and_a_stopped_one_never():
    loop, answers = EventLoop(), []
    server = _server({'hang': [[1.0, 3.0]]}, loop)

    def reply(task, ok, error, busy):
        answers.append(loop.now())
    loop.at(0.5, server.submit, Task(1, 1, 'sort', 1.0, 100, 1.0), 0.0, reply)
    loop.at(2.0, server.submit, Task(1, 2, 'sort', 0.1, 100, 0.1), 0.0, reply)
    loop.run(10.0)
    assert answers == [pytest.approx(3.1), pytest.approx(3.5)]
    assert server.probe_done(2.0) == pytest.approx(3.0005)
    stopped = _server({'stop': 1.0}, loop)
    assert stopped.probe_done(2.0) is None


def test_a_hung_server_reports_the_work_of_a_task_it_did_across_the_hang_not_the_hang():
    """As the node's server does (core/load/pauses.py): a task timed across a stop of its
    process measured the stop, so the work reported is the task's own."""
    loop = EventLoop()
    server = _server({'cpu': 1.0, 'hang': [[1.0, 3.0]]}, loop)
    reply = lambda task, ok, error, busy: None      # noqa: E731
    loop.at(0.0, server.submit, Task(1, 1, 'sort', 0.2, 100, 0.2), 0.0, reply)   # not timed
    loop.at(0.5, server.submit, Task(1, 2, 'sort', 1.0, 100, 1.0), 0.0, reply)   # across it
    loop.run(10.0)
    assert server.queue.times.get('sort') == pytest.approx(1.0)


def test_median_interval_by_order_statistics():
    """n = 30: the 10th and 21st values (P = 0.957), the sign test's."""
    median, low, high = stats.median_interval(range(1, 31))
    assert (median, low, high) == (15.5, 10, 21)
    assert stats.median_interval([None]) == (None, None, None)


def test_t_quantiles_and_the_paired_interval():
    assert stats.t_quantile(29) == pytest.approx(2.0452, abs=1e-3)
    assert stats.t_quantile(5) == pytest.approx(2.5706, abs=2e-3)
    rng = random.Random(1)
    a = [rng.gauss(10, 3) for _ in range(30)]
    mean, low, high = stats.paired(a, [x - 1.0 + rng.gauss(0, 0.1) for x in a])
    assert low < 1.0 < high and high - low < 0.2


def test_generated_scenarios_repeat_with_their_seed_and_load_as_testbed_files():
    assert generate.generated(5) == generate.generated(5)
    assert generate.generated(5) != generate.generated(6)
    for seed in range(1, 41):
        sc = generate.scenario('gen:%d' % seed)
        assert sc.of_role('robot') and len(sc.of_role('server')) >= 2
    assert generate.expand(['gen:3-5', 'near_equal']) == ['gen:3', 'gen:4', 'gen:5',
                                                          'near_equal']


def test_the_same_seed_gives_the_same_figures_and_another_seed_others():
    sc = scenario({'robot1 server1': [{'at': 0, 'delay': 2, 'jitter': 0.5}],
                   'robot1 server2': [{'at': 0, 'delay': 3, 'jitter': 0.5},
                                      {'at': 20, 'down': True}, {'at': 30, 'down': False}]},
                  servers={1: {}, 2: {}}, duration=40.0)
    sc.suite['measure_from'] = 5.0
    model = Model.load()
    runs = [figures(simulate(sc, model, seed, ['fleet']), 'fleet') for seed in (1, 1, 2)]
    assert runs[0] == runs[1] and runs[0] != runs[2]
    assert runs[0].tasks > 50 and runs[0].failed == 0


def test_the_oracle_follows_the_nearest_server_and_a_peer_switches_often():
    sc = scenario({'robot1 server1': [{'at': 0, 'delay': 2}, {'at': 20, 'delay': 9}],
                   'robot1 server2': [{'at': 0, 'delay': 5}]},
                  servers={1: {}, 2: {}}, duration=40.0)
    sc.suite['measure_from'] = 5.0
    model = Model.load()
    oracle = figures(simulate(sc, model, 1, ['oracle_fleet']), 'oracle_fleet')
    assert oracle.switches * 35 / 60.0 == pytest.approx(1.0)   # one move, at 20 s
    assert oracle.reaction < 0.6
    rr = figures(simulate(sc, model, 1, ['round_robin']), 'round_robin')
    assert rr.switches > 100 and rr.mean > oracle.mean


def test_a_kind_is_loaded_when_a_probe_first_announces_it_and_its_first_task_waits():
    class Warm(_Model):
        warm = {'image': 0.1}
    loop, answers = EventLoop(), []
    host = Scenario({'hosts': {'manager': {'role': 'manager'},
                               's': {'role': 'server', 'id': 1, 'cpu': 0.5,
                                     'cpu_period': 1.0}}}).hosts['s']
    server = SimServer(loop, host, Warm(), Streams(1))
    server.probe(7, [('image', 1.0)])           # 0.1 CPU s at half a core: until 0.2 s
    server.probe(8, [('image', 1.0)])           # announced again: loaded once
    loop.at(0.05, server.submit, Task(7, 1, 'image', 0.05, 100, 0.05), 0.0,
            lambda task, ok, error, busy: answers.append(loop.now()))
    loop.run(5.0)
    assert answers == [pytest.approx(0.3, abs=1e-3)]


def test_a_variant_may_switch_a_mechanism_of_the_rule_off_and_a_wrong_one_is_named():
    sc = scenario({'robot1 server1': [{'at': 0, 'delay': 2, 'jitter': 0.5}],
                   'robot1 server2': [{'at': 0, 'delay': 2.2, 'jitter': 0.5}]},
                  servers={1: {}, 2: {}}, duration=40.0)
    sc.suite['measure_from'] = 5.0
    model = Model.load()
    kept = figures(simulate(sc, model, 1, ['fleet']), 'fleet')
    loose = figures(simulate(sc, model, 1, ['fleet~keep']), 'fleet~keep')
    assert kept.switches < loose.switches       # near-equal servers: keep holds it still
    with pytest.raises(ValueError, match='no mechanism spread'):
        variant('fleet~spread')


def test_a_measured_part_that_is_empty_is_an_error_naming_both_numbers():
    short = scenario({}, duration=32.0)
    short.suite['measure_from'] = 35
    with pytest.raises(ValueError, match=r'measure_from \(35 s\).*duration \(32 s\)'):
        measured_window(short)
    with pytest.raises(ValueError, match='nothing is measured'):
        simulate(short, Model.load(), 1, ['fleet'])


def test_changes_before_the_measured_part_are_warned_about_and_later_ones_not():
    data = scenario({'robot1 server1': [{'at': 0, 'delay': 5}, {'at': 20, 'delay': 9},
                                        {'at': 50, 'delay': 5}]},
                    servers={1: {}, 2: {'stop': 10}}, duration=90.0)
    start, warnings = measured_window(data)
    assert start == 35.0
    assert len(warnings) == 2, warnings
    assert 'server2 stops at 10 s' in warnings[0] and 'link robot1-server1 at 20 s' in \
        warnings[1], warnings


def test_the_table_names_the_variant_to_pick_or_says_there_is_no_difference():
    def runs(means):
        return dict((seed, {'mean': m}) for seed, m in enumerate(means, start=1))
    seeds = [1, 2, 3, 4, 5]
    oracle = runs([0.010] * 5)
    clear = {'oracle_fleet': oracle, 'fleet': runs([0.0101, 0.0102, 0.0100, 0.0101, 0.0102]),
             'prequal': runs([0.0110, 0.0111, 0.0112, 0.0110, 0.0111])}
    assert report.pick(clear, seeds).startswith('Pick: fleet, its mean 9.'), \
        report.pick(clear, seeds)
    noisy = {'oracle_fleet': oracle, 'fleet': runs([0.0100, 0.0110, 0.0100, 0.0110, 0.0105]),
             'prequal': runs([0.0110, 0.0100, 0.0110, 0.0100, 0.0106])}
    assert report.pick(noisy, seeds).startswith('Pick: no difference beyond the noise')
