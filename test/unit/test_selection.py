from server_select.core.selection import Selection
from server_select.core.task_flow import LOCAL, NO_SERVER


def test_select_mode_follows_flags_for_this_robot_only():
    s = Selection(1, 'select')
    assert s.target() == NO_SERVER and not s.ready(set())
    assert s.on_flag(2, 5) is False and s.target() == NO_SERVER
    assert s.on_flag(1, 3) is True and s.target() == 3 and s.ready(set())
    assert s.on_flag(1, 3) is False
    assert s.on_flag(1, 2) is True and s.switches == 1


def test_a_flag_naming_no_server_makes_the_robot_not_ready():
    s = Selection(1, 'select')
    s.on_flag(1, 3)
    s.on_flag(1, NO_SERVER)
    assert s.target() == NO_SERVER and not s.ready({3})
    s.on_flag(1, 3)
    assert s.switches == 1   # leaving NO_SERVER is not a switch between servers


def test_fixed_mode_ignores_flags_and_waits_for_its_server_to_answer():
    s = Selection(1, 'fixed', fixed_server=2)
    s.on_flag(1, 3)
    assert s.target() == 2
    assert not s.ready({1, 3}) and s.ready({2})


def test_local_mode_is_always_ready():
    s = Selection(1, 'local')
    assert s.target() == LOCAL and s.ready(set())
