"""bench-capacity's variants: besides the static assignment, any variant of the scenario
suite whose robots select on hosts of their own (its profile and parameters)."""

import pytest

from server_select.bench import capacity


def test_the_capacity_bench_runs_any_suite_variant_that_selects_on_hosts_of_its_own():
    assert capacity.parse(['--variants', 'fleet_6hz,static,prequal']).variants == [
        'fleet_6hz', 'static', 'prequal']
    for other in ('oracle_fleet', 'fleet_pi3_busy', 'fixed', 'nonsense'):
        with pytest.raises(SystemExit):
            capacity.parse(['--variants', other])
