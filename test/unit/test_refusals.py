"""Parameters with no effect where they are set are named (core/robot/refusals.py)."""

from server_select.core.robot.refusals import FLEET_KNOBS, ineffective, refusal
from server_select.core.settings import default


def found(profile, **explicit):
    def get(name):
        return explicit[name] if name in explicit else default(name, profile)
    return [name for name, _ in ineffective(get, explicit.__contains__)]


def test_ranking_knobs_set_on_a_robot_that_chooses_per_task_are_refused():
    assert found('fleet', hysteresis=0.001, dwell=2.0, statistic='median') == \
        ['dwell', 'hysteresis', 'statistic']
    assert found('fleet', policy='prequal', contender_rate=0, margin_z=2.0) == ['margin_z']


def test_the_same_knobs_under_a_ranking_policy_pass():
    assert found('paper', policy='hysteresis', hysteresis=0.001, dwell=2.0, margin_z=2.0) == []
    assert found('fleet', policy='hysteresis', fail_fast=2, passive=True) == []


def test_a_fleet_robot_that_follows_its_manager_may_keep_the_profile_s_probing():
    # (with no rule of its own every server is a contender: probed at ~contender_rate)
    assert found('fleet', policy='mean') == []
    assert found('fleet', policy='hysteresis', contender_rate=10) == []


def test_probe_rate_under_contender_pacing_and_a_blind_least_latency_are_refused():
    assert found('fleet', probe_rate=5.0) == ['probe_rate']
    assert found('fleet', probe_rate=5.0, contender_rate=0) == []
    assert found('fleet', load_aware=False) == ['load_aware']
    assert found('paper', policy='least_latency') == ['load_aware']     # the paper's default
    assert found('fleet') == []


def test_the_refusal_names_each_parameter_and_why():
    line = refusal([('dwell', 'a setting of policy hysteresis')])
    assert '~dwell (a setting of policy hysteresis)' in line
    assert refusal([]) is None


def test_what_the_fleet_rule_fixes_is_refused_and_its_knobs_are_not():
    assert found('fleet', eject_time=2.0, retry_factor=3.0, background_rate=2.0) == \
        ['background_rate', 'eject_time', 'retry_factor']
    assert found('fleet', policy='prequal', contender_rate=0, eject_time=2.0) == []
    assert found('fleet', window=3.0, contender_rate=2.0, hedge=False, max_in_flight=2,
                 fresh_factor=1.0, retry_budget=0.2) == []
    assert len(FLEET_KNOBS) <= 6
