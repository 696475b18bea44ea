"""Graph names shared by every node (README, "Nodes").

All names are relative so that they follow the node's namespace and can be remapped.
"""

SELECTION_TOPIC = 'server_select_flag'
SORT_TASK_TOPIC = 'data'
SORT_RESULT_TOPIC = 'processed_data'
TASK_REPORT_TOPIC = 'task_report'
IMAGE_TASK_TOPIC = 'task_image'
IMAGE_RESULT_TOPIC = 'processed_image'
DETECTIONS_TOPIC = 'detections'
FOUND_TARGETS_TOPIC = 'found_targets'
KNOWN_TARGETS_SERVICE = '~known_targets'


def probe_service(server_id):
    """Name of the LatencyProbe service hosted by ``server_id``."""
    return 'latency_S%d' % server_id


def sample_topic(robot_id, server_id):
    """Name of the topic carrying the latency samples of one (robot, server) pair."""
    return 'latency_R%dS%d' % (robot_id, server_id)
