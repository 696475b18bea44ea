"""The robot's probe loop (ros/probe_loop.py) when a connection with a probe out is closed
elsewhere (its proxy renewed as the fleet's servers restart) and the next connection gets
the same descriptor number: the stale probe ends, the new one is sent, the loop lives.
(Before: 'FD is already registered', then a KeyError that ended the probe thread: a robot
of the short soak probed nothing after a key rotation.)"""

import socket

from server_select.ros.probe_loop import ProbeLoop


class Proxy(object):
    def __init__(self, sock):
        self.sock = sock

    def send(self, _request):
        return self.sock

    def departed(self, sent):
        return sent

    def reconnect(self):
        pass


def test_a_connection_number_reused_while_a_probe_was_out_ends_that_probe_only():
    errors, ended = [], []
    loop = ProbeLoop(lambda: None, lambda: None, errors.append)
    old, _old_peer = socket.socketpair()
    number = old.fileno()
    first = loop.start_probe(Proxy(old), 'probe 1', 5.0,
                             lambda *answer: ended.append(('first', answer[2])))
    old.close()                                   # renewed elsewhere, probe 1 still out
    new, _new_peer = socket.socketpair()
    if new.fileno() != number:                    # the kernel gave another number
        new, _other = socket.socketpair()
    assert new.fileno() == number
    second = loop.start_probe(Proxy(new), 'probe 2', 5.0,
                              lambda *answer: ended.append(('second', answer[2])))
    assert first.finished and not second.finished
    assert [(who, str(error)) for who, error in ended] == \
        [('first', 'its connection was closed')]
    loop._finish(second, None, None, None)        # the second ends as any probe does
    assert [who for who, _ in ended] == ['first', 'second'] and errors == []
