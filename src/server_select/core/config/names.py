"""Graph names shared by every node (docs/design.md, "Nodes").

All names are relative so that they follow the node's namespace and can be remapped. Also
the ids that stand for no server in messages (the unit tests pin them equal to
``TaskReport``'s and ``SelectionFlag``'s).
"""

NO_SERVER = -1      # TaskReport.NO_SERVER, SelectionFlag.NO_SERVER: no server
LOCAL = -2          # TaskReport.LOCAL: the robot did the work itself

# ~policy names of the rules a robot applies per task itself: the fleet profile's, and the
# league's peers (core/peers/balancers.py holds them)
FLEET_RULE = 'least_latency'
PEERS = ('p2c_peak_ewma', 'least_request', 'prequal', 'round_robin', 'replicate')
PER_TASK_RULES = (FLEET_RULE,) + PEERS

SELECTION_TOPIC = 'server_select_flag'
SORT_TASK_TOPIC = 'data'
SORT_RESULT_TOPIC = 'processed_data'
TASK_REPORT_TOPIC = 'task_report'
IMAGE_TASK_TOPIC = 'task_image'
IMAGE_RESULT_TOPIC = 'processed_image'
DETECTIONS_TOPIC = 'detections'
FOUND_TARGETS_TOPIC = 'found_targets'
KNOWN_TARGETS_SERVICE = '~known_targets'
SAMPLES_TOPIC = 'latency_samples'       # fleet profile: one batch per robot probe round
TASK_SAMPLES_TOPIC = 'task_samples'     # ~passive: robots' answered tasks as samples
RANKINGS_TOPIC = 'robot_rankings'       # ~sample_stream view: each robot's own ranking
SERVERS_TOPIC = 'fleet_servers'         # fleet profile: the servers the manager lists
ANNOUNCE_TOPIC = 'server_announcements'  # each server's own, latched: "I am in the fleet"
GROUPS_TOPIC = 'group_assignments'      # grouped deployments: robots to server groups
MASTER_PID_TOPIC = 'master_pid'         # the watcher's news of the master (a restart)


def probe_service(server_id):
    """Name of the LatencyProbe service hosted by ``server_id``."""
    return 'latency_S%d' % server_id


def sample_topic(robot_id, server_id):
    """Name of the topic carrying the latency samples of one (robot, server) pair."""
    return 'latency_R%dS%d' % (robot_id, server_id)


def server_topic(server_id, topic):
    """Direct routing: ``topic`` of one server's own tasks (``server_3/data``)."""
    return 'server_%d/%s' % (server_id, topic)


def robot_topic(robot_id, topic):
    """Direct routing: ``topic`` of one robot's own results (``robot_1/processed_data``)."""
    return 'robot_%d/%s' % (robot_id, topic)


def probe_server_id(service, fleet_ns='/'):
    """The server id of a probe service's resolved name in ``fleet_ns``, else None."""
    prefix = fleet_ns.rstrip('/') + '/latency_S'
    rest = service[len(prefix):] if service.startswith(prefix) else ''
    return int(rest) if rest.isdigit() and str(int(rest)) == rest else None
