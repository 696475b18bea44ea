"""What ``top`` shows (core/observe/fleet_view.py): robots, servers, switches, alerts."""

from server_select.core.observe.fleet_view import FleetView, Load


def row(lines, head, key):
    """The row of ``key`` in the table under the header starting with ``head``."""
    start = next(i for i, line in enumerate(lines) if line.startswith(head))
    for line in lines[start + 1:]:
        if not line.strip():
            break
        if line.split()[0] == str(key):
            return line.split()
    raise AssertionError('no row %s under %s in\n%s' % (key, head, '\n'.join(lines)))


def test_robots_and_servers_as_their_reports_and_probes_say():
    view = FleetView()
    for t in range(10):
        view.probe(1, True, Load(2, 1, 1, 0.75), float(t))
        view.probe(2, True, Load(0, 0, 2, 0.0), float(t))
        view.task(1, 1, 1, True, float(t))
        view.task(2, 2, 2, t % 2 == 0, float(t))
    view.flag(1, 1, [1, 2], 9.0)
    view.sample(1, 1, True, 0.0042, 9.0)
    lines = view.lines(10.0)
    assert lines[0].startswith('server_select top: 2 servers (2 up), 2 robots')
    assert row(lines, 'ROBOT', 1)[:6] == ['1', '1', '1', '2', '4.2', '1.0']
    assert row(lines, 'ROBOT', 2)[1] == '2' and row(lines, 'ROBOT', 2)[5] == '5'   # failed
    assert row(lines, 'SERVER', 1)[:6] == ['1', 'up', '2', '1/1', '0.75', '1.0']
    assert row(lines, 'SERVER', 1)[6:] == ['1']
    assert row(lines, 'SERVER', 2)[3] == '0/2' and row(lines, 'SERVER', 2)[6:] == ['2']


def test_a_server_is_gone_when_its_probe_fails_or_after_two_silent_seconds():
    view = FleetView()
    view.probe(2, True, Load(0, 0, 1, 0.0), 0.0)
    assert row(view.lines(1.9), 'SERVER', 2)[1] == 'up'
    assert row(view.lines(2.1), 'SERVER', 2)[1] == 'GONE'     # silent for 2 s: gone too
    view.probe(1, True, Load(0, 0, 1, 0.0), 0.0)
    view.probe(1, True, Load(0, 0, 1, 0.0), 1.0)
    view.probe(1, False, None, 2.0, 'no answer within 0.5 s')     # its newest probe failed
    lines = view.lines(2.1)
    assert row(lines, 'SERVER', 1)[1] == 'GONE'
    assert [a for a in lines if 'server 1 gone: no answer within 0.5 s' in a]
    assert len([a for a in view.lines(5.0) if 'server 1 gone' in a]) == 1     # said once
    view.probe(1, True, Load(0, 0, 1, 0.0), 6.0)
    lines = view.lines(6.0)
    assert row(lines, 'SERVER', 1)[1] == 'up' and [a for a in lines if 'is back' in a]


def test_a_switch_shows_with_the_reason_the_robot_logged():
    view = FleetView()
    view.task(1, 2, 2, True, 0.0)
    view.task(1, 3, 3, True, 5.0)
    assert ' '.join(row(view.lines(6.0), 'ROBOT', 1)[6:]) == '1 s ago, 2 -> 3'
    view.log('robot 1: sort tasks go to server 1 now (server 1 faster than 3 by 4.2 ms)', 7.0)
    view.task(1, 1, 1, True, 7.1)
    switch = ' '.join(row(view.lines(8.0), 'ROBOT', 1)[6:])
    assert switch == '1 s ago, 3 -> 1: server 1 faster than 3 by 4.2 ms', switch


def test_alerts_for_a_robot_deciding_alone_ignored_messages_and_a_clean_leave():
    view = FleetView()
    view.log('robot 2: no fresh flag from /manager for 3 s: ranking servers from its own '
             'probes', 1.0)
    view.log('manager: ignored a sample on latency_R1S1 published by /spoofer (robot 1 is '
             '/robot1)', 2.0)
    view.announcement(3, 0.0, 3.0)
    lines = view.lines(3.0)
    alerts = lines[lines.index('ALERTS') + 1:]
    assert alerts == ['-2 s  robot 2 decides alone (no fresh flag)',
                      '-1 s  manager ignored a sample on latency_R1S1 from /spoofer',
                      '+0 s  server 3 left the fleet (clean shutdown)'], alerts
    assert row(lines, 'SERVER', 3)[1] == 'GONE'


def test_a_switch_the_log_did_not_explain_shows_the_flags_reason():
    """A per-task robot's flag carries its own reason: top shows it at the switch, whether
    the flag or the first task there is heard first."""
    view = FleetView()
    view.task(1, 2, 2, True, 0.0)
    view.flag(1, 3, [1, 3, 2], 1.0, 'server 3 faster than 2 by 0.4 ms')
    view.task(1, 3, 3, True, 1.1)
    assert view.robots[1].switch == (1.1, 2, 3, 'server 3 faster than 2 by 0.4 ms')
    view.task(1, 1, 1, True, 5.0)
    view.flag(1, 1, [1, 3, 2], 5.1, 'server 1 faster than 3 by 0.2 ms')
    assert view.robots[1].switch == (5.0, 3, 1, 'server 1 faster than 3 by 0.2 ms')
    assert any('5 s ago, 3 -> 1: server 1 faster' in line for line in view.lines(10.0))


def test_rates_count_over_what_the_view_heard_when_that_is_shorter_than_its_window():
    """(``top --once --seconds 5`` showed 1.0 tasks a second for robots sending 2.)"""
    view = FleetView(window=10.0)
    for n in range(10):                  # 2 a second for 5 s
        view.task(1, 1, 1, True, 100.0 + 0.5 * n)
    lines = view.lines(105.0)
    assert 'rates over 5 s' in lines[0]
    assert row(lines, 'ROBOT', 1)[4] == '2.0'
    for n in range(10, 40):              # and on, for 20 s in all: over the window
        view.task(1, 1, 1, True, 100.0 + 0.5 * n)
    assert row(view.lines(120.0), 'ROBOT', 1)[4] == '2.0'
