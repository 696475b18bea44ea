"""Every node parameter: its default and its parser, in one table (no rospy).

:data:`PARAMS` is the one place a default is written: nodes read parameters through it
(``server_select.ros.node.param``), launch files leave an argument empty to mean "the
node's default", and the evaluation takes its defaults from it.
"""

import collections

from server_select.core.fleet.groups import parse_groups
from server_select.core.fleet.leases import LEASE_PERIODS
from server_select.core.ranking.policy import POLICIES
from server_select.core.ranking.window import STATISTICS
from server_select.core.config.params import (one_of, parse_bool, parse_count, parse_id,
                                              parse_members, parse_mode, parse_names,
                                              parse_node_names, parse_non_negative,
                                              parse_node_pattern, parse_number,
                                              parse_plugins, parse_positive, parse_positive_int,
                                              parse_path, parse_publisher, parse_text)

REQUIRED = object()

Param = collections.namedtuple('Param', 'default parse doc')

DEFAULT_CASCADE = 'haarcascade_frontalface_default.xml'
# the largest frame taken by default: 1920x1080 fits, and a Raspberry Pi 3 server holds a
# few (16.7 MP frames took one past 1 GB, with 22 s of detection each)
MAX_IMAGE_PIXELS = 1 << 21

# Every node parameter: default (REQUIRED: none), parser, meaning. A flat table.
PARAMS = {
    'robot_id': Param(REQUIRED, parse_id, "this robot's id"),
    'server_id': Param(REQUIRED, parse_id, "this server's id"),
    'robots': Param(REQUIRED, parse_members, 'ids of the robots (fleet: [] = whoever sends '
                    'samples)'),
    'servers': Param(REQUIRED, parse_members, 'ids of the servers (fleet: [] = those the '
                     'manager announces)'),
    'profile': Param('paper', one_of('paper', 'fleet'), 'a set of defaults: the paper as '
                     'written, or the fleet layout (PROFILES)'),
    'routing': Param('broadcast', one_of('broadcast', 'direct'), 'tasks on one topic for '
                     'every server, or on the addressed server\'s own topic'),
    'sample_stream': Param('pair', one_of('pair', 'robot', 'view'), 'probe samples on one '
                           'topic per (robot, server) pair, one batch per probe round per '
                           'robot, or (view) the robot\'s own ranking when it changes (its '
                           'batches still go out for recorders)'),
    'view_rate': Param(1.0, parse_positive, 'sample_stream view: the robot\'s ranking also '
                       'goes to the manager this often when unchanged (Hz)'),
    'flag_stream': Param('shared', one_of('shared', 'robot'), 'flags on one topic for every '
                         'robot, or each on its robot\'s own latched topic '
                         '(robot_<r>/server_select_flag; a copy still on the shared one for '
                         'recorders)'),
    'discover': Param(False, parse_bool, 'robot: also probe the servers the manager lists; '
                      'manager: list the servers that announce themselves'),
    'groups': Param(REQUIRED, parse_groups, 'server groups {group id: [server ids]}; the '
                    'first server of a group is its representative'),
    'group': Param(None, parse_id, 'grouped: this manager ranks the robots of group {group}'),
    'top_manager_node': Param('', parse_publisher, 'grouped: follow the group assignments '
                              'of this node (empty: not grouped)'),
    'group_manager_node': Param('/manager_g{group}', parse_publisher, 'grouped: flags '
                                "count only from the manager of the robot's group"),
    'group_margin': Param(0.001, parse_non_negative, 'a robot moves to a nearer group only '
                          'when its representative is nearer by this (s)'),
    'announce_period': Param(2.0, parse_positive, "period of a server's announcement on "
                             'server_announcements (s); its lease is %d periods' % LEASE_PERIODS),
    'mode': Param('select', parse_mode, 'select (follow the manager), fixed or local'),
    'fixed_server': Param(None, parse_id, 'target in fixed mode (default: first server)'),
    'probe_rate': Param(1.0, parse_positive, 'probes per second to each server (Hz)'),
    'probe_timeout': Param(0.5, parse_positive, 'a probe without answer after this fails (s)'),
    'contender_rate': Param(0.0, parse_non_negative, 'adaptive probing (a rule per task): '
                            'probes per second to each contender (where tasks go and the '
                            'servers near the best), at most 2 per task sent; 0: every '
                            'server at ~probe_rate'),
    'background_rate': Param(0.5, parse_positive, 'adaptive probing: probes per second to '
                             'each server that is not a contender (Hz)'),
    'contender_budget': Param(20.0, parse_positive, 'adaptive probing: probes per second to '
                              'all contenders together, at most (Hz)'),
    'sort_tasks': Param(True, parse_bool, 'send sort tasks'),
    'task_rate': Param(2.0, parse_positive, 'sort tasks per second (Hz)'),
    'task_size': Param(1000, parse_positive_int, 'values per sort task'),
    'task_timeout': Param(2.0, parse_positive, 'a task without result after this fails (s)'),
    'tasks': Param(0, parse_count, 'stop each stream after this many tasks (0: never)'),
    'start_delay': Param(0.0, parse_non_negative, 'seconds to wait before the first task'),
    'report_listeners': Param([], parse_node_names, 'the first task waits until these nodes '
                              'hear task_report, and the task topics they subscribe to (a '
                              'recorder that must see every task; empty: start at once)'),
    'summary_period': Param(10.0, parse_positive, 'period of the log summary (s)'),
    'seed': Param(None, parse_id, 'task data random seed (default: the robot id)'),
    'image_source': Param('', parse_path, 'folder, video file or search:<area.yaml>'),
    'frame_rate': Param(10.0, parse_positive, 'camera frames offloaded per second (Hz)'),
    'image_encoding': Param('bgr8', one_of('bgr8', 'rgb8', 'mono8'), 'encoding of sent frames'),
    'robot_index': Param(0, parse_count, "this robot's strip of a search area"),
    'robot_count': Param(1, parse_positive_int, 'number of strips of a search area'),
    'speed': Param(200.0, parse_positive, 'sweep speed over a search area (area pixels/s)'),
    'sweep_start': Param(0.0, parse_non_negative, 'when the sweep of a search area began '
                         '(epoch s; 0: at the node\'s start), to share a clock with others'),
    'merge_radius': Param(150.0, parse_positive, 'detections this close are one target (px)'),
    'detector': Param('haar', one_of('haar', 'hog'), 'Haar cascade or HOG people detector'),
    'cascade': Param(DEFAULT_CASCADE, parse_path, 'cascade file name or path'),
    'scale_factor': Param(1.2, parse_positive, 'cascade scale step'),
    'min_neighbors': Param(5, parse_positive_int, 'cascade neighbours for a detection'),
    'min_size': Param(24, parse_positive_int, 'smallest target (px)'),
    'max_task_len': Param(100000, parse_positive_int, 'longer sort tasks are refused from '
                          'their length, unread (a Raspberry Pi 3 holds a 1e5-value task in '
                          '4 MB)'),
    'work_delay': Param(0.0, parse_non_negative, 'each task takes this much longer (s): a '
                        'slower or busier machine; with ~test_knobs, rosparam set changes '
                        'it at run time'),
    'check_every': Param(0.0, parse_non_negative, 'server: while no robot sends here, time '
                         'a copy of the last task of a kind not timed for this long (s; and '
                         'at most 5 % of a worker), so that probes say what one takes now '
                         '(0: never)'),
    'test_knobs': Param(False, parse_bool, 'server: follow ~work_delay at run time (tests and '
                        'the testbed); off, it is read once at start and no other node can '
                        'slow the server down'),
    'queue_size': Param(100, parse_positive_int, 'task subscriber queue length'),
    'workers': Param(0, parse_count, 'tasks a server works on at once (0: the cores it may '
                     "use, its cgroup's CPU quota rounded up)"),
    'max_queue': Param(100, parse_positive_int, 'tasks waiting for a worker; more are answered '
                       'busy'),
    'max_queue_bytes': Param(32 << 20, parse_positive_int, 'memory the tasks waiting for a '
                             'worker may hold (bytes); one more is answered busy'),
    'load_aware': Param(False, parse_bool, 'rank servers by round trip + wait for a worker + '
                        'work per task (from its probe answers), announce its task rate in '
                        'probes, give each task its deadline, and let attempt deadlines '
                        'follow that estimate'),
    'max_in_flight': Param(0, parse_count, 'tasks of a stream out at once; a send finding '
                           'them all out waits for one to end, the newest frame winning '
                           '(0: no limit)'),
    'fresh_factor': Param(0.0, parse_non_negative, 'load-aware: a camera frame is worth an '
                          'answer until the next frame is due, and at least this many times '
                          'the round trip + work of the server it goes to; one that server '
                          'cannot start in time is refused busy (0: the task timeout)'),
    'retry_budget': Param(0.1, parse_non_negative, 're-sends and hedges: at most this share '
                          'of the tasks sent in the last 10 s, plus 2; a task stranded on a '
                          'server that stopped answering goes elsewhere without it '
                          '(0: no limit)'),
    'max_image_pixels': Param(MAX_IMAGE_PIXELS, parse_positive_int, 'larger frames are '
                              'refused (a raw one from its length, unread); 1920x1080 fits'),
    'image_topic': Param('', parse_text, 'camera frames from this sensor_msgs/Image or '
                         'CompressedImage topic (newest frame wins)'),
    'image_transport': Param('raw', one_of('raw', 'compressed'), 'how frames travel'),
    'jpeg_quality': Param(80, parse_count, 'JPEG quality of compressed frames (0-100)'),
    'window': Param(5.0, parse_positive, 'latency sample window (s); least_latency: an answer '
                    'older than this no longer counts'),
    'window_samples': Param(0, parse_count, "a pair's window also keeps its newest this many "
                            'samples, up to ~window_max old (for servers probed rarely)'),
    'window_max': Param(8.0, parse_positive, 'the oldest a sample kept by ~window_samples may '
                        'be (s, at least ~window)'),
    'publish_rate': Param(1.0, parse_positive, 'periodic selection flag rate (Hz)'),
    'update_rate': Param(10.0, parse_positive, 're-evaluation rate between samples (Hz)'),
    'hysteresis': Param(0.0, parse_non_negative, 'keep the current server while within this '
                        'of the best (s); 0: the paper'),
    'policy': Param('mean', one_of(*POLICIES), 'which ranked server a robot gets: mean (the '
                    'paper) or hysteresis (docs/design.md, "Policies"); or a rule the '
                    'robot applies per task: least_latency (docs/selection.md), or a peer: '
                    'p2c_peak_ewma, least_request, prequal, round_robin, replicate '
                    '(docs/league.md)'),
    'statistic': Param('mean', one_of(*STATISTICS), 'what the window ranks by (policies '
                       'mean, hysteresis)'),
    'dwell': Param(0.0, parse_non_negative, 'policy hysteresis: no move within this long of '
                   'the last one (s)'),
    'margin_z': Param(0.0, parse_non_negative, 'policy hysteresis: the margin grows by this '
                      'many standard errors of the two means'),
    'fail_fast': Param(0, parse_count, 'rank no server whose newest this many samples failed '
                       '(0, the paper: only when no good sample is left in the window)'),
    'passive': Param(False, parse_bool, "robots' answered tasks are latency samples too "
                     '(on task_samples, to the manager)'),
    'task_memory': Param(0.0, parse_non_negative, 'with ~passive: what a server\'s tasks cost '
                         'above its probes is added to its probes, fading with this time '
                         'constant (s) once its tasks stop (0: not at all)'),
    'manager_timeout': Param(3.0, parse_positive, 'a flag older than this is stale: the robot '
                             'ranks its servers itself (s)'),
    'eject_time': Param(1.0, parse_positive, 'first ejection of a failing server (s); doubles '
                        'with each ejection in a row'),
    'eject_max': Param(30.0, parse_positive, 'longest ejection (s)'),
    'retry_factor': Param(5.0, parse_positive, "an attempt's deadline: this x the server's "
                          'recent p99 task round trip'),
    'hedge': Param(False, parse_bool, 'also send a task still unanswered after its '
                   "server's p95 plus its median task round trip to the next server "
                   '(first answer wins)'),
    'retry_floor': Param(0.25, parse_positive, "shortest attempt deadline (s)"),
    'manager_node': Param('/manager', parse_publisher, 'flags count only from this node '
                          '(*: from any)'),
    'robot_node': Param('first', parse_node_pattern, 'samples of robot {id} count from the '
                        'first node that sends them while it lives (first), only from this '
                        'node or its namespace (/name{id}), or from any (*)'),
    'task_plugins': Param('', parse_plugins, 'task types added by plug-in (module:Class ...)'),
    'fleet_ns': Param('/', parse_text, 'namespace of the fleet-level topics and services'),
    'fleet_key': Param('', parse_path, 'the fleet key, or this role\'s key file (make_key '
                       '[--role]): messages leave signed, only signed ones count (empty: off)'),
    'fleet_key_next': Param('', parse_path, 'a second key file also accepted (rotation)'),
    'require_key': Param(False, parse_bool, 'refuse to start without ~fleet_key (a fleet '
                         'that must not run unsigned)'),
    'fleet_key_max_age': Param(30.0, parse_positive, 'a signed message older or newer than '
                               'this by our clock is refused (s)'),
    'master_check': Param(60.0, parse_positive, 'period of a node\'s own check for a restarted '
                          'roscore (s, +-20 %); it checks at once when the watcher says so'),
    'master_watch': Param(1.0, parse_positive, 'the watcher\'s (the manager\'s) period of the '
                          'check for a restarted roscore (s); it tells the others'),
    'scenario': Param(REQUIRED, parse_path, 'scenario YAML file'),
    't0': Param(REQUIRED, parse_number, 'scenario time zero (epoch s)'),
    'duration': Param(30.0, parse_positive, 'how long to listen or measure (s)'),
    'output': Param('', parse_path, 'also write the result as JSON here'),
    'end_launch': Param(False, parse_bool, 'when done, end the roslaunch that started the node'),
    'nodes': Param(REQUIRED, parse_names, 'node names to measure'),
    'delay': Param(5.0, parse_positive, 'wait this long before measuring (s)'),
    'area': Param(REQUIRED, parse_path, 'search area YAML file'),
    'radius': Param(150.0, parse_positive, 'a report this close to a target finds it (px)'),
    'timeout': Param(180.0, parse_positive, 'give up after this long (s)'),
}


# Profiles: sets of defaults, one argument apart (``~profile``, launch ``profile:=``). A
# parameter set explicitly always wins. ``paper`` is the paper as written.
PROFILES = {
    'paper': {},
    'fleet': {'routing': 'direct', 'sample_stream': 'view', 'flag_stream': 'robot',
              'discover': True,
              'robots': [], 'servers': [],
              # one rule, chosen by the robot per task (docs/selection.md; the league:
              # docs/league.md)
              'policy': 'least_latency',
              'window': 2.0, 'probe_rate': 4.0,
              # adaptive probing: docs/design.md, "Adaptive probing"
              'contender_rate': 4.0, 'background_rate': 1.0,
              'hedge': True,
              # capacity: docs/design.md, "Capacity and overload"
              'load_aware': True, 'max_in_flight': 1, 'fresh_factor': 2.0,
              # a server's idle kinds checked: docs/design.md, "Capacity and overload"
              'check_every': 0.5},
}


def default(name, profile='paper'):
    """The default of parameter ``name`` in ``profile`` (KeyError for an unknown name)."""
    return PROFILES[profile].get(name, PARAMS[name].default)
