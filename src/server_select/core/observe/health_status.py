"""What each node says on ``/diagnostics`` (no rospy, no messages): a level, a message and
key-value pairs, from what the node knows.

The levels are ``diagnostic_msgs/DiagnosticStatus``'s (a unit test pins them equal). A
healthy fleet is all OK: a level above it names what is wrong and where.
"""

OK, WARN, ERROR, STALE = 0, 1, 2, 3


def server_status(load, busy, done):
    """A server: ``load`` (queued, in_service, workers, utilization), ``busy`` tasks
    answered busy and ``done`` tasks done since the last status."""
    values = [('queued', load.queued), ('in service', '%d of %d workers' % (
        load.in_service, load.workers)), ('utilization', '%.2f' % load.utilization),
        ('done since last', done), ('answered busy since last', busy)]
    if busy:
        return WARN, 'overloaded: %d tasks answered busy (its robots send them elsewhere)' \
            % busy, values
    return OK, 'serving: %d queued, %d of %d workers busy' % (
        load.queued, load.in_service, load.workers), values


def robot_status(server, reason, sent, failed, unusable, keyed):
    """A robot: tasks go to ``server`` (an id; a text such as ``'the robot itself'``;
    None: none usable) for ``reason``; ``sent`` and ``failed`` tasks since the last status;
    ``unusable`` {server: its health state} of the servers tasks may not go to now."""
    out = sorted(unusable)
    where = 'server %s' % server if isinstance(server, int) else server
    values = [('server', server if server is not None else 'none'), ('reason', reason or '-'),
              ('tasks sent since last', sent), ('failed since last', failed),
              ('servers not in use', ', '.join('%s (%s)' % (s, unusable[s]) for s in out)
               or 'none'), ('fleet key', 'on' if keyed else 'off')]
    if server is None:
        return ERROR, 'no usable server: tasks fail or wait', values
    if failed:
        return WARN, '%d of %d tasks failed since the last status' % (failed, sent), values
    if out:
        return WARN, 'server %s not answering; tasks go to %s' % (
            ', '.join(map(str, out)), where), values
    return OK, 'tasks go to %s (%s)' % (where, reason or 'selected'), values


def fleet_statuses(views, servers):
    """The manager's status of each server from its robots' views: ``views`` {robot:
    (ranked servers, servers left out: no good answer in the window, or ejected)}; ``servers`` every
    server known. ``{server: (level, message, values)}``."""
    out = {}
    for server in sorted(servers):
        ranked = sorted(r for r, (good, _) in views.items() if server in good)
        failing = sorted(r for r, (_, bad) in views.items() if server in bad)
        values = [('ranked by robots', ' '.join(map(str, ranked)) or 'none'),
                  ('not answering robots', ' '.join(map(str, failing)) or 'none')]
        if ranked:
            out[server] = (OK, 'answering %d robots' % len(ranked), values)
        elif failing:
            out[server] = (ERROR, 'not answering robots %s (no good probe in the window, or '
                           'ejected)' % ', '.join(map(str, failing)), values)
        else:
            out[server] = (STALE, 'no robot has heard from it', values)
    return out
