"""The largest message of each of the fleet's own types that a node takes on a topic with
no limit of its own: a longer one is refused from its length, before a byte of it is read
or decoded (`ros/bounded_read.py`). Tasks have theirs from `~max_task_len` and
`~max_image_pixels`, probes 64 KiB.

One server's or robot's message (an announcement, a report, a found target) has 64 KiB;
lists over the fleet (rankings, samples, flags, members, groups) have room for thousands
of servers: 1,000 servers' take about 40 KB. (No rospy.)
"""

KIB = 1 << 10

MESSAGE_LIMITS = dict(('server_select/%s' % name, most) for name, most in (
    ('ServerAnnouncement', 64 * KIB),
    ('TaskReport', 64 * KIB),
    ('FoundTarget', 64 * KIB),
    ('LatencySample', 64 * KIB),
    ('LatencySamples', 1024 * KIB),
    ('RobotRanking', 1024 * KIB),
    ('SelectionFlag', 1024 * KIB),
    ('FleetServers', 1024 * KIB),
    ('Detections', 1024 * KIB),
    ('GroupAssignments', 4096 * KIB),
))


def table():
    """The lines of docs/parameters.md that say these limits."""
    return [__doc__.split('\n\n', 1)[0].replace('\n', ' ').strip(), '',
            '| message type | largest taken |', '|---|---|'] + [
        '| `%s` | %d KiB |' % (kind, most // KIB) for kind, most in sorted(MESSAGE_LIMITS.items())]
