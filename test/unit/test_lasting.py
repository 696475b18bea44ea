from server_select.core.util.lasting import Lasting


class Clock(object):
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_a_condition_counts_once_it_has_held_for_the_grace_and_then_again_after_another():
    clock = Clock()
    lasting = Lasting(5.0, clock)
    seen = []
    for step in range(23):           # every half second for 11 s
        seen.append(lasting.held('s1', True))
        clock.now += 0.5
    assert [i * 0.5 for i, held in enumerate(seen) if held] == [5.0, 10.0]


def test_a_false_look_starts_the_count_again_and_keys_are_apart():
    clock = Clock()
    lasting = Lasting(2.0, clock)
    assert not lasting.held('a', True) and not lasting.held('b', True)
    clock.now += 1.5
    assert not lasting.held('a', False)
    clock.now += 1.0
    assert not lasting.held('a', True) and lasting.held('b', True)
    clock.now += 2.0
    assert lasting.held('a', True)
    lasting.forget('a')
    assert not lasting.held('a', True)
