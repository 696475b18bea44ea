"""A server's queue shared fairly between robots: the round robin in seconds of work, the
longest queue giving room to the others, the wait a task is admitted by, every task out
once."""

import random
import threading

from hypothesis import given, settings, strategies as st

from server_select.core.load.service_times import ServiceTimes
from server_select.core.load.work_queue import WorkQueue

from support.clock import Clock


def queue(work, workers=1, max_queue=100, max_bytes=None):
    """A queue whose kinds are known to take ``work`` ({kind: s}); its pushed-out jobs."""
    times, pushed = ServiceTimes(), []
    for kind, seconds in work.items():
        times.add(kind, seconds)
    q = WorkQueue(workers, max_queue, times, Clock(), max_bytes=max_bytes,
                  on_pushed_out=lambda job, why: pushed.append((job.item, why)))
    return q, pushed


def taken(q, count):
    out = []
    for _ in range(count):
        job = q.take()
        q.done(job)
        out.append(job.item)
    return out


def test_a_robot_queued_behind_a_flood_is_served_at_the_next_turn():
    q, _ = queue({'big': 0.02, 'small': 0.001})
    for n in range(50):
        assert q.offer('big', ('flood', n), owner=9) is None
    for n in range(3):
        assert q.offer('small', ('robot1', n), owner=1) is None
    order = taken(q, 8)
    assert [item for item in order if item[0] == 'robot1'] == [('robot1', n) for n in range(3)]
    assert order.index(('robot1', 2)) <= 4, order     # FIFO: after all 50 of the flood


def take_in_thread(q):
    """A worker taking from ``q`` in a thread of its own; what it took (a list)."""
    got = []
    worker = threading.Thread(target=lambda: got.append(q.take()), daemon=True)
    worker.start()
    return worker, got


def test_while_another_robot_sends_a_flood_holds_one_worker_of_two_and_alone_both():
    q, _ = queue({'big': 0.2, 'small': 0.001}, workers=2)
    assert q.offer('small', 'r0', owner=1) is None     # robot 1 sends here
    q.done(q.take())
    for n in range(4):
        assert q.offer('big', ('flood', n), owner=9) is None
    assert q.take().item == ('flood', 0)
    worker, got = take_in_thread(q)
    worker.join(0.3)
    assert worker.is_alive() and got == []     # the flood's next waits: one worker is kept
    assert q.offer('small', 'r1', owner=1) is None
    worker.join(5.0)
    assert [job.item for job in got] == ['r1']
    q.done(got[0])
    q._clock.now += 11.0                       # robot 1 silent past the horizon: alone
    assert q.take().item == ('flood', 1)


def test_a_flood_waiting_for_a_worker_takes_it_when_one_of_its_jobs_ends():
    q, _ = queue({'big': 0.2, 'small': 0.001}, workers=2)
    assert q.offer('small', 'r0', owner=1) is None
    q.done(q.take())
    for n in range(2):
        assert q.offer('big', ('flood', n), owner=9) is None
    first = q.take()
    worker, got = take_in_thread(q)
    worker.join(0.3)
    assert worker.is_alive()
    q.done(first, 0.2)
    worker.join(5.0)
    assert [job.item for job in got] == [('flood', 1)]


def test_each_robot_waiting_gets_an_equal_share_of_the_work_whatever_its_tasks_sizes():
    q, _ = queue({'big': 0.03, 'small': 0.01})
    for n in range(40):
        q.offer('big', ('a', n), owner='a')
        q.offer('small', ('b', n), owner='b')
    work = {'a': 0.0, 'b': 0.0}
    for item in taken(q, 30):
        work[item[0]] += 0.03 if item[0] == 'a' else 0.01
    assert abs(work['a'] - work['b']) <= 0.03 + 1e-9, work


def test_a_full_queue_gives_a_place_of_the_longest_to_a_robot_holding_less():
    q, pushed = queue({'sort': 0.001}, max_queue=4)
    for n in range(4):
        assert q.offer('sort', ('flood', n), owner=9) is None
    assert q.offer('sort', ('r1', 0), owner=1) is None
    assert pushed == [(('flood', 3), 'busy: pushed out of the queue by a task of a robot '
                                     'holding less of it')]
    assert q.offer('sort', ('r1', 1), owner=1) is None          # 3 against 1: one more
    assert q.offer('sort', ('r1', 2), owner=1) == 'busy: 4 tasks queued already'  # 2, 2
    assert q.offer('sort', ('flood', 9), owner=9) == 'busy: 4 tasks queued already'
    assert len(pushed) == 2 and q.pushed_out == 2


def test_bytes_are_shared_the_same_way():
    q, pushed = queue({'sort': 0.001}, max_bytes=1000)
    for n in range(4):
        assert q.offer('sort', ('flood', n), owner=9, size=250) is None
    assert q.offer('sort', ('r1', 0), owner=1, size=300) is None
    assert [item for item, _ in pushed] == [('flood', 3), ('flood', 2)]
    assert q.queued_bytes == 800


def test_a_deadline_is_judged_by_the_wait_of_the_robots_own_turn_not_the_whole_queue():
    q, _ = queue({'big': 0.1, 'small': 0.01})
    for n in range(50):                        # 5 s of another robot's work
        q.offer('big', n, owner=9)
    now = q._clock()
    assert q.offer('small', 'r1', deadline=now + 0.5, owner=1) is None
    assert q.offer('big', 'more', deadline=now + 0.5, owner=9).startswith('busy: would finish')


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2 ** 32 - 1))
def test_every_task_offered_is_refused_pushed_out_taken_or_dropped_exactly_once(seed):
    rng = random.Random(seed)
    q, pushed = queue({'a': 0.01, 'b': 0.05}, workers=2, max_queue=6, max_bytes=3000)
    offered, ends = [], []
    for n in range(200):
        if rng.random() < 0.6:
            offered.append(n)
            owner = rng.choice([1, 2, 3, 9, 9, 9])
            why = q.offer(rng.choice('ab'), n, owner=owner, size=rng.randrange(0, 900),
                          deadline=None if rng.random() < 0.5 else q._clock() + 0.3)
            if why is not None:
                ends.append(n)
        elif len(q._queue):
            ends.append(taken(q, 1)[0])
        q._clock.now += rng.random() * 0.02
    ends += [item for item, _ in pushed] + [job.item for job in q.close()]
    assert sorted(ends) == offered
    assert q.queued_bytes == 0


def test_a_robots_task_is_judged_by_what_its_own_tasks_of_the_kind_took():
    q, _ = queue({})
    clock = q._clock
    for n in range(10):                 # robot 9's sorts take 0.5 s, robot 1's 5 ms
        q.offer('sort', n, owner=9, size=400000)
        q.done(q.take(), 0.5)
        q.offer('sort', n, owner=1, size=4000)
        q.done(q.take(), 0.005)
    for n in range(4):
        q.offer('sort', ('flood', n), owner=9, size=400000)
    assert q.offer('sort', 'small', deadline=clock() + 0.3, owner=1, size=4000) is None
    assert q.offer('sort', 'new', deadline=clock() + 0.3, owner=2, size=4000).startswith(
        'busy: would finish')           # not timed yet: the kind's usual work


def test_frames_that_take_the_same_work_get_the_same_share_whatever_their_bytes():
    """(Work estimated from bytes gave a robot sending raw frames a quarter of the turns
    of one sending the same frames as JPEG.)"""
    q, _ = queue({})
    for n in range(40):
        q.offer('image', ('raw', n), owner=1, size=900000)
        q.offer('image', ('jpeg', n), owner=2, size=60000)
    counts = {'raw': 0, 'jpeg': 0}
    for _ in range(40):
        job = q.take()
        q.done(job, 0.1)
        counts[job.item[0]] += 1
    assert abs(counts['raw'] - counts['jpeg']) <= 2, counts
