"""The simulated server against queueing theory: Poisson arrivals at one server running
the package's WorkQueue, the mean wait for a worker over a long run beside the closed
form (M/D/1: Pollaczek-Khinchine; M/M/c: Erlang C), within 3 %."""

import math
import random

import pytest

from server_select.sim.events import EventLoop, Streams
from server_select.sim.server import SimServer
from server_select.sim.tasks import Task
from server_select.testbed.scenario import Host


class _Model(object):
    probe_cpu, cpu_factor, warm = 0.0, 1.0, {}


def mean_wait(workers, arrival_rate, service, customers, seed=1):
    """The mean wait before service of ``customers`` Poisson arrivals; ``service()`` draws
    a task's work (s)."""
    loop = EventLoop()
    host = Host('server1', 'server', 1, 0.0, None, (), (), float(workers), 100.0, None, 0.0)
    server = SimServer(loop, host, _Model(), Streams(seed), max_queue=10 ** 7)
    rng, waits = random.Random(seed), []

    def reply(task, ok, error, busy):
        assert ok and not busy
        waits.append(loop.now() - task.bytes - task.work)    # bytes: the arrival time

    def arrive(n, t):       # (its work drawn as it arrives; all of it its own)
        work = service(rng)
        server.submit(Task(1, n, 'job', work, t, work), 0.0, reply)

    t = 0.0
    for n in range(customers):
        t += rng.expovariate(arrival_rate)
        loop.at(t, arrive, n, t)
    loop.run(t + 1000.0)
    assert len(waits) == customers
    skip = customers // 20                                      # the start-up transient
    return sum(waits[skip:]) / (customers - skip)


def erlang_c_wait(c, arrival_rate, service_rate):
    a = arrival_rate / service_rate
    rho = a / c
    top = a ** c / math.factorial(c) / (1.0 - rho)
    probability = top / (sum(a ** k / math.factorial(k) for k in range(c)) + top)
    return probability / (c * service_rate - arrival_rate)


@pytest.mark.parametrize('rho', [0.5, 0.8])
def test_md1_mean_wait_is_pollaczek_khinchine(rho):
    service = 0.01
    measured = mean_wait(1, rho / service, lambda rng: service, 200000)
    expected = rho * service / (2.0 * (1.0 - rho))
    print('M/D/1 rho %.1f: %.6f s against %.6f s' % (rho, measured, expected))
    assert measured == pytest.approx(expected, rel=0.03)


def test_mmc_mean_wait_is_erlang_c():
    c, service_rate, rho = 3, 100.0, 0.75
    arrival_rate = rho * c * service_rate
    measured = mean_wait(c, arrival_rate, lambda rng: rng.expovariate(service_rate), 200000)
    expected = erlang_c_wait(c, arrival_rate, service_rate)
    print('M/M/3 rho %.2f: %.6f s against %.6f s' % (rho, measured, expected))
    assert measured == pytest.approx(expected, rel=0.03)
