"""The fleet the scale benchmark simulates: servers in equal groups, and each robot's
round trips, which give every robot a different, well separated nearest server (and
group)."""


def base_rtt(robot, server, servers, groups=1):
    """Robot ``robot``'s nearest server is the one with (robot + server) % servers == 0;
    with groups, its nearest group is the one with (robot + group) % groups == 0 (5 ms a
    step), and within a group steps are 0.1 ms."""
    if groups == 1:
        return 1e-3 * (1 + (robot + server) % servers)
    size = servers // groups
    group = (server - 1) // size + 1
    return 1e-3 * (1 + 5 * ((robot + group) % groups) + 0.1 * ((robot + server) % size))


def group_table(servers, groups):
    size = servers // groups
    return dict((g, list(range((g - 1) * size + 1, g * size + 1))) for g in range(1, groups + 1))
