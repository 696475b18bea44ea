import rosgraph

from server_select.ros.graph import ServiceProviders, publisher_of

from support.clock import Clock


class FakeMaster(object):
    def __init__(self):
        self.services, self.calls, self.away = [], 0, False

    def __call__(self):
        self.calls += 1
        if self.away:
            raise rosgraph.MasterError('master away')
        return [], [], self.services


def test_providers_are_looked_up_once_then_again_only_when_asked_and_due():
    clock, master = Clock(), FakeMaster()
    master.services = [['/latency_S1', ['/server1']], ['/latency_S2', []]]
    providers = ServiceProviders('/robot1', period=1.0, clock=clock, system_state=master)
    assert providers.node('/latency_S1') == '/server1' and master.calls == 1
    assert providers.node('/latency_S1') == '/server1' and master.calls == 1
    master.services = [['/latency_S1', ['/server1b']]]       # restarted under another name
    assert providers.node('/latency_S1', refresh=True) == '/server1' and master.calls == 1
    clock.now += 1.0
    assert providers.node('/latency_S1', refresh=True) == '/server1b' and master.calls == 2


def test_unknown_services_cost_one_look_up_per_period_and_a_lost_master_keeps_what_was_known():
    clock, master = Clock(), FakeMaster()
    master.services = [['/latency_S1', ['/server1']]]
    providers = ServiceProviders('/robot1', clock=clock, system_state=master)
    for _ in range(10):
        assert providers.node('/latency_S99') is None
    assert master.calls == 1
    master.away = True
    clock.now += 5.0
    assert providers.node('/latency_S1', refresh=True) == '/server1' and master.calls == 2


def test_publisher_of_a_message():
    class Msg(object):
        pass
    msg = Msg()
    assert publisher_of(msg) == '?'
    msg._connection_header = {'callerid': '/manager'}
    assert publisher_of(msg) == '/manager'
