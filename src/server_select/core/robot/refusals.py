"""Parameters that would do nothing where they are set, or that the fleet's rule fixes
(no rospy).

A robot that chooses per task (``~policy`` least_latency or a peer) ranks nothing by
windows and follows no flags, so the knobs of the ranking policies have no effect on it;
a knob set there would be a mistake that passes in silence. ``least_latency`` has few
knobs (:data:`FLEET_KNOBS`); what else decides where its tasks go has the values the
league measured (docs/selection.md) and is not for setting. A node refuses either at
start, with a line naming the parameter and why (:func:`ineffective`).
"""

from server_select.core.ranking.policy import PER_TASK

# parameter -> why it does nothing for a robot that chooses per task
RANKING_ONLY = {
    'hysteresis': 'the margin of the ranking policies (mean, hysteresis)',
    'dwell': 'a setting of policy hysteresis',
    'margin_z': 'a setting of policy hysteresis',
    'statistic': 'what the ranking policies rank by',
    'passive': 'task samples feed the ranking policies',
    'task_memory': 'a setting of ~passive',
    'fail_fast': 'a setting of the ranking policies',
    'manager_timeout': 'a robot that chooses per task follows no flags',
    'window_samples': 'a rule per task counts the answers of the last ~window s',
    'window_max': 'a setting of ~window_samples',
}
# what least_latency can be told: the parameters that change where a fleet robot's tasks go
FLEET_KNOBS = ('window', 'contender_rate', 'hedge', 'max_in_flight', 'fresh_factor',
               'retry_budget')
# parameter -> what least_latency fixes in its place
FIXED_BY_RULE = {
    'background_rate': 'servers far from the best are probed at the profile\'s rate',
    'contender_budget': 'contenders\' probes follow the robot\'s task rate',
    'eject_time': 'failing servers are ejected as the profile says',
    'eject_max': 'failing servers are ejected as the profile says',
    'retry_factor': 'attempt deadlines follow the servers\' round trips and load',
    'retry_floor': 'attempt deadlines follow the servers\' round trips and load',
}


def not_for_setting(get):
    """``[(name, why)]`` of the robot parameters that are not for setting with the others'
    values (``get(name)``): no effect, or fixed by the rule. The node neither takes them
    nor shows them on the parameter server."""
    found = []
    if get('policy') in PER_TASK:
        found += [(name, '%s; ~policy %s chooses per task' % (why, get('policy')))
                  for name, why in sorted(RANKING_ONLY.items())]
        if get('policy') == 'least_latency':
            found += [(name, 'fixed by least_latency: %s (its knobs: %s)'
                       % (why, ', '.join(FLEET_KNOBS)))
                      for name, why in sorted(FIXED_BY_RULE.items())]
        if get('contender_rate'):
            found.append(('probe_rate', 'probes are paced by ~contender_rate %g'
                          % get('contender_rate')))
    return found


def ineffective(get, is_set):
    """``[(name, why)]`` of the parameters set explicitly (``is_set(name)``) that are not
    for setting (:func:`not_for_setting`), or set to what the rule cannot work with."""
    found = [(name, why) for name, why in not_for_setting(get) if is_set(name)]
    if get('policy') == 'least_latency' and not get('load_aware'):
        found.append(('load_aware', 'least_latency estimates from the servers\' load: false '
                      'would leave it blind'))
    return found


def refusal(found):
    """One line saying what :func:`ineffective` found (None: nothing)."""
    if not found:
        return None
    return 'parameters not for setting here: %s (unset them)' % '; '.join(
        '~%s (%s)' % item for item in found)
