"""The switch table of a recorded run: each change of a robot's task server, with the
reason of the flag that named the new server."""

from server_select.testbed.bag_analysis import Flag, Report
from server_select.testbed.switch_table import switches, table


def report(t, task, server, robot=1):
    return Report(t, robot, task, True, 0.002, server, server, '', 1)


def test_each_task_move_is_a_row_with_the_flags_reason():
    reports = [report(1.0, 1, 2), report(2.0, 2, 2), report(3.0, 3, 3), report(4.0, 4, 3),
               report(5.0, 5, 1), report(7.0, 6, 3), report(5.5, 1, 2, robot=2),
               report(6.0, 2, 1, robot=2)]
    flags = [Flag(0.5, 1, 2, [2, 3], [1e-3, 2e-3], 'the fastest'),
             Flag(3.4, 1, 3, [3, 2], [1e-3, 2e-3], 'server 3 faster than 2 by 0.3 ms'),
             Flag(3.5, 1, 3, [3, 2], [1e-3, 2e-3], 'server 3 faster than 2 by 0.3 ms'),
             Flag(5.2, 1, 1, [3, 1], [1e-3, 1.1e-3],
                  'server 1 faster than 3 by 0.1 ms (2 within the noise: one at random)'),
             Flag(9.0, 1, 3, [3, 1], [1e-3, 1.1e-3], 'later: not this switch')]
    found = switches(reports, flags)
    assert [(s.t, s.robot, s.before, s.after) for s in found] == [
        (3.0, 1, 2, 3), (5.0, 1, 3, 1), (6.0, 2, 2, 1), (7.0, 1, 1, 3)]
    assert found[0].reason == 'server 3 faster than 2 by 0.3 ms'    # flag within 1 s after
    assert found[1].reason.endswith('(2 within the noise: one at random)')
    assert found[2].reason == '(no flag named it)'
    assert found[3].reason == '(no flag named it)'     # the 3.5 flag explained another
    text = table(found, limit=2)
    assert text.splitlines()[0] == '| time s | robot | from | to | reason |'
    assert '| 3.0 | 1 | 2 | 3 | server 3 faster than 2 by 0.3 ms |' in text
    assert text.endswith('2 more switches in report.md')
