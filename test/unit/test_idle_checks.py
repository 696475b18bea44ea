"""A server's checks of an idle kind (core/load/work_queue.py, service_times.py): while
no robot sends to it, it times a copy of a kind's last task, so that its probe answers
say what one takes now, not what its history says."""

from server_select.core.load.service_times import ServiceTimes
from server_select.core.load.work_queue import CHECK, WorkQueue

from support.clock import Clock


def served(queue, clock, seconds, robot=1, kind='sort', tasks=5):
    """``tasks`` tasks of ``robot``, each taking ``seconds``, 0.25 s apart."""
    for _ in range(tasks):
        assert queue.offer(kind, 'task', owner=robot) is None
        job = queue.take(wait=False)
        clock.now += seconds
        queue.done(job, seconds)
        clock.now += 0.25


def checked(queue, clock, seconds, every=5.0, item='copy'):
    """The check due now, worked on for ``seconds``; the job (None: none offered)."""
    if queue.offer_check(every, lambda kind: item) is None:
        return None
    job = queue.take(wait=False)
    clock.now += seconds
    queue.done(job, seconds)
    return job


def test_a_server_nobody_sends_to_times_a_copy_of_an_idle_kinds_last_task():
    clock = Clock()
    queue = WorkQueue(1, 10, ServiceTimes(clock=clock), clock)
    served(queue, clock, 0.001)
    clock.now += 4.0
    assert queue.offer_check(5.0, lambda kind: 'copy') is None     # timed 5 s ago: no
    clock.now += 6.0                  # its tasks no longer arrive (10 s): nobody sends
    finished = queue.finished
    job = checked(queue, clock, 0.030)
    assert (job.kind, job.item, job.owner, job.deadline) == ('sort', 'copy', CHECK, None)
    assert queue.finished == finished           # a check is no task worked on
    assert checked(queue, clock, 0.030) is None  # one every 5 s
    clock.now += 5.0
    checked(queue, clock, 0.030)
    # the newest three: two checks of 30 ms beside a task of 1 ms
    assert queue.load().service == {'sort': 0.030}


def test_no_check_while_a_robot_sends_or_a_worker_is_busy():
    clock = Clock()
    queue = WorkQueue(2, 10, ServiceTimes(clock=clock), clock)
    served(queue, clock, 0.001, kind='image')
    clock.now += 10.0
    queue.announce(2, [('sort', 4.0)])             # robot 2 says it sends here now
    assert queue.offer_check(5.0, lambda kind: 'copy') is None
    clock.now += 3.5                               # its word expired (3 s)
    assert queue.offer('sort', 'task', owner=3) is None
    job = queue.take(wait=False)                   # robot 3's task runs
    assert queue.offer_check(5.0, lambda kind: 'copy') is None
    queue.done(job, None)
    clock.now += 10.5                              # robot 3's tasks no longer arrive
    assert queue.offer_check(5.0, lambda kind: None) is None      # no copy: no check
    assert queue.offer_check(5.0, lambda kind: 'copy') == 'image'  # (still due)
    assert queue.offer_check(0.0, lambda kind: 'copy') is None     # 0: never


def test_checks_say_when_a_slowed_server_recovers_and_while_it_has_not():
    """A server slowed by 25 ms a task, which its robots left after three: left idle,
    its history (mostly before the slowdown) said it was fast again, and robots came back
    every 10 s to slow tasks (the league's loaded_server); checked, it says what a task
    takes now, slow until it recovers, then fast."""
    def reports(every):
        clock = Clock()
        queue = WorkQueue(1, 10, ServiceTimes(clock=clock), clock)
        served(queue, clock, 0.002, tasks=40)
        served(queue, clock, 0.027, tasks=3)           # slowed: robots leave
        seen = []
        for second in range(60):                       # recovered after 30 s
            clock.now += 1.0
            checked(queue, clock, 0.027 if second < 30 else 0.002, every)
            seen.append(queue.load().service['sort'])
        return seen
    unchecked, checks = reports(0.0), reports(5.0)
    assert max(unchecked[15:30]) == 0.002              # slowed, but says fast
    assert min(checks[15:30]) == 0.027                 # slowed, and says so
    assert checks[45:] == [0.002] * 15                 # recovered within two checks


def test_a_simulated_server_checks_as_the_node_does_and_answers_nobody():
    """The simulator's server offers the same queue's check at a probe's answer: slowed by
    25 ms a task at 15 s after its robot left, it says so within two checks, and the
    checks reach no robot and count as no task done."""
    from server_select.sim.events import EventLoop, Streams
    from server_select.sim.server import SimServer
    from server_select.sim.tasks import Task
    from server_select.testbed.scenario import Scenario

    class Model(object):
        probe_cpu, cpu_factor, warm = 0.0005, 1.0, {}

        def shared_delay(self, rng):
            return 0.0

    def reports(every):
        loop, answers, seen = EventLoop(), [], []
        host = Scenario({'hosts': {'manager': {'role': 'manager'}, 's': {
            'role': 'server', 'id': 1, 'work': [{'at': 15, 'delay': 25}]}}}).hosts['s']
        server = SimServer(loop, host, Model(), Streams(1), check_every=every)
        for n in range(4):
            loop.at(0.25 * n, server.submit, Task(1, n, 'sort', 0.001, 100, 0.001), 0.0,
                    lambda task, ok, error, busy: answers.append(task.task_id))
        for second in range(2, 40):
            loop.at(second, lambda: seen.append(server.probe(2, []).service['sort']))
        loop.run(40.0)
        return answers, len(server.completions), seen
    answers, done, checked = reports(5.0)
    assert (answers, done) == ([0, 1, 2, 3], 4)
    assert max(checked[:12]) < 0.002 and min(checked[26:]) > 0.025, checked
    assert max(reports(0.0)[2]) < 0.002        # unchecked: what its history says


def test_a_simulated_check_reruns_the_task_with_the_hosts_share_drawn_anew():
    """A check reruns its kind's last task: what that task takes alone, plus a share of
    the host of its own. A copy of the task's whole work made one draw of a shared CPU
    the idle server's report, with no spread, for as long as nobody sent it a task."""
    from server_select.sim.events import EventLoop, Streams
    from server_select.sim.server import SimServer
    from server_select.sim.tasks import Task
    from server_select.testbed.scenario import Scenario

    class Model(object):
        probe_cpu, cpu_factor, warm = 0.0005, 1.0, {}

        def shared_delay(self, rng):
            return rng.uniform(0.0, 0.001)

    loop, timed = EventLoop(), []
    host = Scenario({'hosts': {'manager': {'role': 'manager'}, 's': {
        'role': 'server', 'id': 1}}}).hosts['s']
    server = SimServer(loop, host, Model(), Streams(1), check_every=0.5)
    add = server.queue.times.add
    server.queue.times.add = lambda kind, seconds, alone=True: (
        timed.append(seconds), add(kind, seconds, alone))
    for n in range(2):       # (a kind's first task is not timed)
        loop.at(0.1 * n, server.submit, Task(1, n, 'sort', 0.004, 100, 0.001), 0.0,
                lambda task, ok, error, busy: None)
    for second in range(1, 10):
        loop.at(second, server.probe, 2, [])
    loop.run(10.0)
    checks = timed[1:]
    assert timed[0] == 0.004 and len(checks) >= 5, timed
    assert all(0.001 <= c < 0.002 for c in checks) and len(set(checks)) == len(checks), checks


def test_checks_take_at_most_a_twentieth_of_a_worker():
    """A kind of 0.2 s tasks is checked every 4 s at most, however short ``every`` is."""
    clock = Clock()
    queue = WorkQueue(1, 10, ServiceTimes(clock=clock), clock)
    served(queue, clock, 0.2)
    clock.now += 10.0
    begun = []
    for _ in range(80):                          # 8 s, asked every 0.1 s
        job = checked(queue, clock, 0.2, every=1.0)
        if job is not None:
            begun.append(round(clock.now, 1))
        clock.now += 0.1
    assert len(begun) == 2 and begun[1] - begun[0] >= 4.0, begun


def test_a_rate_nobody_announces_any_more_is_none_not_a_rounding():
    """Rates announced and withdrawn leave no residue (2.0, 0.7, 2.2 announced, then none:
    2.2e-16 tasks a second left in floating point; in the simulated loaded_server, 8.9e-16:
    a server nobody sent to counted as sent to, and was never checked)."""
    from server_select.core.load.demand import Demand
    demand = Demand()
    demand.announce(1, [('sort', 2.0)], 0.0)
    demand.announce(2, [('sort', 0.7)], 0.0)
    demand.announce(1, [('sort', 2.2)], 0.1)
    demand.announce(1, [], 0.5)
    demand.announce(2, [], 0.5)
    assert demand.rates(1.0) == {}
