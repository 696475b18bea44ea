"""Fleet membership by leases (core/fleet/leases.py)."""

import pytest

from server_select.core.fleet.leases import Leases


def test_an_announced_server_is_a_member_until_its_lease_ends():
    leases = Leases()
    assert leases.renew(3, '/server3', 10.0, 1.5) == (True, None)
    assert leases.renew(1, '/server1', 10.2, 1.5) == (True, None)
    assert leases.members() == [1, 3]
    assert leases.expire(11.49) == []
    assert leases.expire(11.5) == [3]
    assert leases.members() == [1]


def test_an_announcement_renews_the_lease_without_a_change():
    leases = Leases()
    leases.renew(2, '/server2', 0.0, 1.5)
    assert leases.renew(2, '/server2', 1.0, 1.5) == (False, None)
    assert leases.expire(2.0) == []          # would have ended at 1.5 without the renewal
    assert leases.expire(2.5) == [2]


def test_a_leaving_server_is_gone_at_once_and_leaving_twice_changes_nothing():
    leases = Leases()
    leases.renew(2, '/server2', 0.0, 1.5)
    assert leases.renew(2, '/server2', 0.1, 0.0) == (True, None)
    assert leases.members() == []
    assert leases.renew(2, '/server2', 0.2, 0.0) == (False, None)
    assert leases.expire(100.0) == []


def test_an_id_is_its_first_nodes_until_it_leaves_or_its_lease_ends():
    leases = Leases()
    leases.renew(2, '/server2', 0.0, 1.5)
    assert leases.renew(2, '/other', 0.5, 1.5) == (False, '/server2')
    assert leases.renew(2, '/other', 0.6, 0.0) == (False, '/server2')   # nor end it
    assert (leases.members(), leases.holder(2)) == ([2], '/server2')
    assert leases.renew(2, '/server2', 0.7, 0.0) == (True, None)         # its own leave
    assert leases.renew(2, '/other', 0.8, 1.5) == (True, None)
    assert leases.renew(2, '/server2', 1.0, 1.5) == (False, '/other')
    assert leases.renew(2, '/server2', 2.4, 1.5) == (False, None)         # lease ended
    assert leases.holder(2) == '/server2'
    assert (leases.holder(2, 3.8), leases.holder(2, 3.9)) == ('/server2', None)   # till 3.9


@pytest.mark.parametrize('lease', [-1.0, float('nan')])
def test_a_lease_that_is_not_a_duration_is_refused(lease):
    with pytest.raises(ValueError):
        Leases().renew(1, '/server1', 0.0, lease)
