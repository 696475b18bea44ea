from server_select.core.robot.health import DOWN, EJECTED, HEALTHY, PROBATION, ServerHealth

from support.clock import Clock


def make(**kwargs):
    """Servers 1, 2, 3, each of which has answered a probe."""
    clock = Clock(0.0)
    health = ServerHealth([1, 2, 3], clock=clock, **kwargs)
    for server in (1, 2, 3):
        health.probe_ok(server)
    return health, clock


def test_a_failure_ejects_at_once_and_only_that_server():
    h, clock = make(base=1.0)
    ejection = h.failure(2, 'task timeout')
    assert ejection == (2, 1.0, 'task timeout')
    assert h.order([3, 2, 1]) == [3, 1]
    assert h.failure(2, 'again') is None          # already ejected: no second ejection
    assert h.failure(9, 'unknown server') is None
    assert h.state(1) == HEALTHY and h.state(2) == EJECTED and h.state(9) is None


def test_probation_needs_good_probes_then_one_good_task():
    h, clock = make(base=1.0, probation_probes=2)
    h.failure(1)
    clock.now = 0.999
    assert h.state(1) == EJECTED
    clock.now = 1.0
    assert h.state(1) == PROBATION and not h.usable(1)
    h.probe_ok(1)
    assert not h.usable(1)
    h.probe_ok(1)
    assert h.usable(1) and h.order([1, 2]) == [1, 2]
    assert h.task_ok(1) is True and h.state(1) == HEALTHY
    assert h.task_ok(1) is False                 # already healthy


def test_ejection_time_doubles_in_a_row_up_to_the_longest_and_resets_when_healthy():
    h, clock = make(base=1.0, longest=3.0, probation_probes=0)
    times = []
    for _ in range(4):
        ejection = h.failure(1)
        times.append(ejection.seconds)
        clock.now += ejection.seconds              # back on probation...
        assert h.state(1) == PROBATION             # ... and failing again
    assert times == [1.0, 2.0, 3.0, 3.0]
    h.task_ok(1)
    assert h.failure(1).seconds == 1.0


def test_probes_while_ejected_for_a_failed_task_do_not_count_toward_probation():
    h, clock = make(base=1.0, probation_probes=1)
    h.failure(3)
    h.probe_ok(3)
    clock.now = 1.0
    assert not h.usable(3)
    h.probe_ok(3)
    assert h.usable(3)


def test_a_server_that_never_answered_is_down_not_ejected_for_longer_and_longer():
    clock = Clock(0.0)
    h = ServerHealth([1, 2], base=1.0, longest=30.0, probation_probes=2, clock=clock)
    h.probe_ok(1)
    assert h.failure(2, 'unavailable') == (2, 0.0, 'unavailable')   # said once ...
    for _ in range(20):                               # ... not again, and no back-off
        clock.now += 1.0
        assert h.failure(2, 'unavailable') is None
    assert h.state(2) == DOWN and h.order([2, 1]) == [1]
    h.probe_ok(2)                                     # it came up: two good probes
    assert not h.usable(2)
    h.probe_ok(2)
    assert h.order([2, 1]) == [2, 1]
    assert h.task_ok(2) is True and h.state(2) == HEALTHY
    assert h.failure(2, 'timeout') == (2, 1.0, 'timeout')   # it answered: ejected now


def test_a_new_server_is_a_candidate_before_any_evidence():
    h = ServerHealth([1], clock=Clock(0.0))
    assert h.usable(1) and h.state(1) == HEALTHY


def test_a_server_ejected_for_its_probes_is_back_once_they_answer_again():
    h, clock = make(base=1.0, longest=30.0, probation_probes=2)
    for _ in range(5):                              # a long outage: 1, 2, 4, 8, 16 s
        ejection = h.failure(1, 'probe failed', probe=True)
        clock.now += ejection.seconds
    assert ejection.seconds == 16.0 and h.state(1) == PROBATION
    assert h.failure(1, 'probe failed', probe=True).seconds == 30.0
    clock.now += 1.0                                # the link is back 1 s into 30
    h.probe_ok(1)
    assert not h.usable(1)                          # one answer is not yet a row
    h.probe_ok(1)
    assert h.state(1) == PROBATION and h.usable(1)  # two in a row: a candidate at once
    assert h.task_ok(1) and h.state(1) == HEALTHY


def test_an_outage_counts_as_one_ejection_when_a_task_fails_on_the_return():
    h, clock = make(base=1.0, longest=30.0, probation_probes=2)
    for _ in range(5):                              # a long outage: 1, 2, 4, 8, 16 s
        ejection = h.failure(1, 'probe failed', probe=True)
        clock.now += ejection.seconds
    h.probe_ok(1)
    h.probe_ok(1)                                   # back
    assert h.usable(1)
    # its first task was late (written into a connection the outage had stalled)
    assert h.failure(1, 'no answer within 0.25 s').seconds == 2.0
    clock.now += 1.0
    h.probe_ok(1)
    h.probe_ok(1)
    assert h.state(1) == EJECTED            # a task's failure: it serves its time
    clock.now += 1.0
    h.probe_ok(1)
    h.probe_ok(1)
    assert h.state(1) == PROBATION and h.usable(1)
    assert h.task_ok(1) and h.state(1) == HEALTHY
    assert h.failure(1, 'no answer within 0.25 s').seconds == 1.0


def test_a_server_ejected_for_its_tasks_serves_its_time_whatever_its_probes_say():
    h, clock = make(base=1.0, longest=30.0, probation_probes=2)
    assert h.failure(1, 'no answer within 2 s').seconds == 1.0
    for _ in range(5):
        h.probe_ok(1)                               # its probe service still answers
    assert h.state(1) == EJECTED and not h.usable(1)
    clock.now += 1.0
    assert h.state(1) == PROBATION
    # probes in a row: a failure between two answers starts the count again
    h2, _ = make(base=1.0, longest=30.0, probation_probes=2)
    h2.failure(2, 'probe failed', probe=True)
    h2.probe_ok(2)
    h2.failure(2, 'probe failed', probe=True)      # still ejected: the row is broken
    h2.probe_ok(2)
    assert not h2.usable(2)
    h2.probe_ok(2)
    assert h2.usable(2)
    # a task that fails while it is ejected for its probes: it serves its time
    h2.failure(2, 'probe failed', probe=True)
    h2.failure(2, 'no answer within 2 s')
    h2.probe_ok(2)
    h2.probe_ok(2)
    assert h2.state(2) == EJECTED


def test_with_every_server_out_those_whose_probes_answer_are_used_anyway():
    h, clock = make(base=1.0)
    for server in (1, 2, 3):
        h.failure(server, 'task late')              # a task late on each in turn
    h.failure(3, 'probe failed', probe=True)        # and 3's link is down
    assert not any(h.usable(s) for s in (1, 2, 3))
    assert h.order([2, 3, 1]) == [2, 1]             # panic: the ranking's order, 3 out
    assert h.state(1) == h.state(2) == EJECTED      # panic ejects and heals nothing
    h.probe_ok(3)
    assert h.order([3, 2, 1]) == [3, 2, 1]          # its probe answers again
    clock.now = 1.0
    h.probe_ok(1)
    h.probe_ok(1)
    assert h.usable(1) and h.order([3, 2, 1]) == [1]   # one usable again: panic over


def test_servers_that_never_answered_are_no_panic_candidates():
    h = ServerHealth([1, 2], clock=Clock(0.0))
    h.failure(1, 'probe failed', probe=True)
    h.failure(2, 'probe failed', probe=True)
    assert h.order([1, 2]) == []


def test_a_probe_still_out_ejects_but_leaves_a_lone_server_to_panic():
    # a busy server on a loaded host answers a probe late: the next is not sent and the
    # robot counts it failed (still out). That ejects the server as a failed probe does,
    # and other servers take the tasks; but no answer has said it is unreachable, so
    # when none is usable tasks still go to it (camera.test's only server, in CI: its
    # frames failed "no server selected"). The probe's own failure, later, does say so.
    h, clock = make(base=1.0)
    h.failure(1, 'previous probe still in progress', late=True)
    assert h.state(1) == EJECTED and h.order([1, 2]) == [2]
    h.failure(2, 'task late')
    h.failure(3, 'task late')
    assert h.order([1, 2, 3]) == [1, 2, 3]             # none usable: panic keeps 1
    h.failure(1, 'probe timed out', probe=True)        # its probe failed: unreachable
    assert h.order([1, 2, 3]) == [2, 3]
    h.probe_ok(1)
    h.probe_ok(1)                                      # answers again, two in a row:
    assert h.state(1) == PROBATION                     # back as a late probe's ejection
