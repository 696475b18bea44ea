"""What each node says on /diagnostics: OK when healthy, and a level above it that names
what is wrong and where."""

from server_select.core.load.work_queue import Load
from server_select.core.observe.health_status import (ERROR, OK, STALE, WARN, fleet_statuses,
                                                      robot_status, server_status)


def load(queued=0, in_service=1, workers=2, utilization=0.3):
    return Load(queued, in_service, workers, 0.0, {}, utilization, {})


def test_a_server_is_ok_serving_and_warns_when_it_answers_busy():
    level, message, values = server_status(load(), busy=0, done=12)
    assert (level, message) == (OK, 'serving: 0 queued, 1 of 2 workers busy')
    assert ('done since last', 12) in values
    level, message, _ = server_status(load(queued=9, in_service=2), busy=4, done=3)
    assert level == WARN and message.startswith('overloaded: 4 tasks answered busy')


def test_a_robot_says_where_its_tasks_go_and_warns_of_failures_and_servers_out():
    level, message, values = robot_status(2, 'the fastest', 10, 0, {}, True)
    assert (level, message) == (OK, 'tasks go to server 2 (the fastest)')
    assert ('fleet key', 'on') in values
    level, message, _ = robot_status(2, 'the fastest', 10, 0, {3: 'ejected'}, True)
    assert (level, message) == (WARN, 'server 3 not answering; tasks go to server 2')
    level, message, _ = robot_status(2, 'the fastest', 10, 3, {}, False)
    assert (level, message) == (WARN, '3 of 10 tasks failed since the last status')
    assert robot_status(None, '', 0, 0, {}, False)[0] == ERROR
    assert robot_status('the robot itself', 'mode local', 5, 0, {}, False)[1] == \
        'tasks go to the robot itself (mode local)'


def test_the_manager_marks_a_server_no_robot_can_reach_as_an_error():
    views = {1: ({1, 2}, {3}), 2: ({2}, {1, 3})}
    statuses = fleet_statuses(views, {1, 2, 3, 4})
    assert statuses[1][0] == OK and statuses[2][:2] == (OK, 'answering 2 robots')
    assert statuses[3][:2] == (ERROR, 'not answering robots 1, 2 (no good probe in the '
                                      'window, or ejected)')
    assert statuses[4][0] == STALE
