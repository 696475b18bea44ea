"""What ``reload_keys`` says of the fleet's answers (server_select.ros.key_reload.report):
every node told, alike, or the status that stops an operator before the next step."""

from server_select.ros.key_reload import report
from server_select.srv import ReloadKeysResponse


def answer(signs='aaa', accepts=('aaa', 'bbb'), ok=True, message='changed'):
    return ReloadKeysResponse(ok, message, signs, list(accepts))


def test_every_node_alike_is_good_and_one_line_each():
    lines, good = report({'/robot1/reload_keys': answer(), '/top/reload_keys': answer(''),
                          '/manager/reload_keys': answer(accepts=('bbb', 'aaa'))})
    assert good and len(lines) == 3
    assert 'signs with -' in lines[2] and 'admits aaa bbb' in lines[1]


def test_a_failed_silent_or_different_node_makes_it_fail_and_says_which():
    for odd, said in ((answer(ok=False, message='keys kept: ~fleet_key: cannot read'),
                       'FAILED'),
                      ('no answer within 5 s', 'no answer'),
                      (answer(signs='ccc'), 'disagree'),
                      (answer(accepts=('aaa',)), 'disagree')):
        lines, good = report({'/robot1/reload_keys': answer(), '/server2/reload_keys': odd})
        assert not good and said in '\n'.join(lines), (odd, lines)
    assert report({}) == ([], False)
