"""Parameters that would do nothing where they are set (no rospy).

A robot that chooses per task (``~policy`` hot_cold or a peer) ranks nothing by windows
and follows no flags, so the knobs of the ranking policies have no effect on it; a knob
set there would be a mistake that passes in silence. A node refuses one at start, with a
line naming it and why (:func:`ineffective`).
"""

from server_select.core.selection.policy import PER_TASK

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
}


def ineffective(get, is_set):
    """``[(name, why)]`` of the parameters set explicitly (``is_set(name)``) that have no
    effect with the others' values (``get(name)``)."""
    found = []
    if get('policy') in PER_TASK:
        found += [(name, '%s; ~policy %s chooses per task' % (why, get('policy')))
                  for name, why in sorted(RANKING_ONLY.items()) if is_set(name)]
        if is_set('probe_rate') and get('contender_rate'):
            found.append(('probe_rate', 'probes are paced by ~contender_rate %g'
                          % get('contender_rate')))
    elif get('contender_rate'):
        found.append(('contender_rate', 'adaptive probing follows the estimates of a rule '
                      'that chooses per task; ~policy %s ranks by windows (set it to 0)'
                      % get('policy')))
    if get('policy') == 'hot_cold' and not get('load_aware'):
        found.append(('load_aware', 'hot_cold estimates from the servers\' load: false '
                      'would leave it blind'))
    return found


def refusal(found):
    """One line saying what :func:`ineffective` found (None: nothing)."""
    if not found:
        return None
    return 'parameters with no effect here: %s (unset them)' % '; '.join(
        '~%s (%s)' % item for item in found)
