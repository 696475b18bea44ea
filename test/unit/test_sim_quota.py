"""The CFS quota model: full speed while the quota lasts, a stall to the next period after."""

import pytest

from server_select.sim.quota import CpuQuota


def test_a_short_task_on_an_idle_capped_host_takes_its_own_cpu_time():
    quota = CpuQuota(0.2, 0.1)                   # 20 ms per 100 ms
    assert quota.run(0.010, 0.001) == pytest.approx(0.011)
    assert quota.run(0.050, 0.005) == pytest.approx(0.055)


def test_a_task_that_spends_the_quota_waits_for_the_next_period():
    quota = CpuQuota(0.2, 0.1)
    assert quota.run(0.0, 0.015) == pytest.approx(0.015)
    # 5 ms left in this period, the other 5 ms at the start of the next one
    assert quota.run(0.020, 0.010) == pytest.approx(0.105)
    # 5 ms of this period's quota are gone: 15 now, the other 15 in the next period
    assert quota.run(0.105, 0.030) == pytest.approx(0.215)


def test_what_a_period_leaves_unused_is_lost_and_the_phase_shifts_the_periods():
    quota = CpuQuota(0.5, 0.01, phase=0.004)      # periods start at 4, 14, 24 ... ms
    assert quota.run(0.0, 0.004) == pytest.approx(0.004)   # a new period at 4 ms
    # 4 ms to the period's end at 34, 5 in the next, the last 3 after 44
    assert quota.run(0.030, 0.012) == pytest.approx(0.047)
    # a long task: 40 periods of 25 ms, the last ending 25 ms into its period
    assert CpuQuota(0.25, 0.1).run(0.0, 1.0) == pytest.approx(3.925)


@pytest.mark.parametrize('share, period', [(0.0, 0.1), (1.0, 0.1), (0.5, 0.0)])
def test_a_quota_outside_its_domain_is_refused(share, period):
    with pytest.raises(ValueError):
        CpuQuota(share, period)


def test_back_to_back_work_runs_at_the_share_whatever_the_rounding_of_its_boundaries():
    quota = CpuQuota(0.2, 0.1, phase=0.0317)
    t = 0.0
    for _ in range(3000):                       # ends often land on a period's end
        t = quota.run(t, 0.0013)
    assert t == pytest.approx(3000 * 0.0013 / 0.2, rel=0.01)
