"""A testbed run's prefix (testbed/traces.py): its own, and no other run's beginning."""

from server_select.testbed import traces


def test_a_runs_prefix_is_its_own_and_begins_no_other_runs(monkeypatch):
    prefixes = []
    for pid in (123, 1234, 12345, 4194304):
        monkeypatch.setattr(traces.os, 'getpid', lambda pid=pid: pid)
        prefixes.append(traces.own_prefix('sscapacity'))
    assert prefixes == ['sscap00123', 'sscap01234', 'sscap12345', 'sscap94304']
    # a device is the prefix and a host's number: within the kernel's 15 characters, and
    # no run's devices or namespaces fall under another run's prefix
    assert all(len(p + '-s99') <= 15 for p in prefixes)
    assert not any(a != b and (b + '12').startswith(a) for a in prefixes for b in prefixes)
