"""Per-robot run summary built from selection flags and task reports (no rospy)."""

import collections

from server_select.core.ranking.rank import NO_SERVER
from server_select.core.settings import default
from server_select.core.util.stats import summarize
from server_select.core.util.tables import markdown_table


def switch_count(servers, kinds=None):
    """Changes in ``servers``, the servers a robot sent its tasks to in task order, within
    each kind (``kinds``: the tasks' kinds in the same order; None: one kind): a robot whose
    frames go to one server and its sort tasks to another switches neither. No server, or
    the robot's own CPU, is left out. The one count of switches of the demo's table, the
    bag analysis and the league."""
    last, count = {}, 0
    for server, kind in zip(servers, kinds if kinds is not None else [None] * len(servers)):
        if server is None or server < 0:
            continue
        count += last.get(kind, server) != server
        last[kind] = server
    return count


def _servers_and_kinds(sent_to):
    """([server], [kind]) of ``{task id: (server, kind)}`` in task order."""
    ordered = [sent_to[task] for task in sorted(sent_to)]
    return [s for s, _ in ordered], [k for _, k in ordered]


class RunReport(object):
    """Accumulates what a run's topics say about each robot."""

    def __init__(self, timeout=default('task_timeout')):
        self.timeout = timeout   # a failed task's round trip in the statistics
        self.flags = {}
        self.sent_to = collections.defaultdict(dict)   # robot -> {task id: (server, kind)}
        self.tasks = collections.defaultdict(list)
        self.probes = collections.defaultdict(list)

    def add_flag(self, robot_id, server_id, ranking, means):
        self.flags[robot_id] = (server_id, list(ranking), list(means))

    def add_task(self, robot_id, ok, rtt, server_id, error, task_id=None, sent_to=None,
                 kind=None):
        """A task report: answered by ``server_id``; ``sent_to`` the server it was first
        sent to (its ``task_id`` orders them), which switches are counted from, per
        ``kind``."""
        self.tasks[robot_id].append((ok, rtt, server_id, error))
        if task_id is not None and sent_to is not None:
            self.sent_to[robot_id][task_id] = (sent_to, kind)

    def add_probe(self, robot_id, server_id, ok, rtt):
        self.probes[robot_id].append((server_id, ok, rtt))

    def robot_summary(self, robot_id):
        tasks = self.tasks.get(robot_id, [])
        selected, ranking, means = self.flags.get(robot_id, (None, [], []))
        errors = collections.Counter(t[3] for t in tasks if not t[0])
        return {
            'robot': robot_id,
            'selected': selected,
            'ranking': ranking,
            'mean_latency_ms': [m * 1e3 for m in means],
            'switches': switch_count(*_servers_and_kinds(self.sent_to[robot_id])),
            'tasks': len(tasks),
            'ok': sum(1 for t in tasks if t[0]),
            'failed': sum(1 for t in tasks if not t[0]),
            'errors': dict(errors),
            'servers_used': sorted(set(t[2] for t in tasks if t[0])),
            'rtt': summarize([t[1] if t[0] else self.timeout for t in tasks]),
            'probes': len(self.probes.get(robot_id, [])),
            'probes_failed': sum(1 for p in self.probes.get(robot_id, []) if not p[1]),
            'probe_rtt': summarize([p[2] for p in self.probes.get(robot_id, []) if p[1]]),
        }

    def summaries(self):
        robots = set(self.flags) | set(self.tasks) | set(self.probes)
        return [self.robot_summary(r) for r in sorted(robots)]

    def table(self, summaries=None):
        """A Markdown table, one row per robot (of ``summaries``, default: now)."""
        rows = []
        for s in self.summaries() if summaries is None else summaries:
            ranking = ', '.join('S%d %.2f' % (srv, ms)
                                for srv, ms in zip(s['ranking'], s['mean_latency_ms'])) or '-'
            selected = s['selected'] not in (None, NO_SERVER)
            rows.append(['R%d' % s['robot'], 'S%d' % s['selected'] if selected else 'none',
                         ranking, s['switches'], s['tasks'], s['ok'], s['failed']]
                        + _ms(s['rtt'], ('median', 'p95', 'p99', 'max'))
                        + ['%d (%d)' % (s['probes'], s['probes_failed'])]
                        + _ms(s['probe_rtt'], ('median', 'p99')))
        return markdown_table(
            ('robot', 'selected', 'ranking (mean probe RTT ms)', 'switches', 'tasks', 'ok',
             'failed', 'task RTT median ms', 'p95', 'p99', 'max', 'probes (failed)',
             'probe RTT median ms', 'p99'), rows)

    @staticmethod
    def legend():
        """What the columns of :meth:`table` mean, one line each."""
        return '\n'.join('%s: %s' % pair for pair in LEGEND)

    def verdict(self, summaries=None):
        """One line of what the run found: tasks, failures, round trip, the selection (of
        ``summaries``, default: now; give the table's, so that the two agree)."""
        summaries = self.summaries() if summaries is None else summaries
        tasks = sum(s['tasks'] for s in summaries)
        failed = sum(s['failed'] for s in summaries)
        rtt = summarize([t[1] if t[0] else self.timeout
                         for r in sorted(self.tasks) for t in self.tasks[r]])
        selected = ', '.join(
            'R%d -> %s' % (s['robot'], 'S%d' % s['selected']
                           if s['selected'] not in (None, NO_SERVER) else 'none')
            for s in summaries)
        return ('%d robots sent %d tasks, %d failed%s; selected now: %s; switches in all: %d'
                % (len(summaries), tasks, failed,
                   ', median task round trip %.2f ms' % (rtt['median'] * 1e3) if rtt['n']
                   else '', selected or 'none', sum(s['switches'] for s in summaries)))


LEGEND = (
    ('selected', "the server the manager's last flag for the robot selects (a fleet robot's "
     'own choice: it also weighs load and noise, so it may not be the ranking\'s first)'),
    ('ranking', "that flag's servers, best first, with the statistic it ranks them by "
     '(mean probe round trip over the window, ms)'),
    ('switches', 'changes of the server a robot sent its tasks to (counted as analyze and '
     'the league count them)'),
    ('tasks, ok, failed', "the robot's task reports; failed: no right answer within the task "
     'timeout'),
    ('task RTT', 'send to checked result, ms; a failed task counts at the task timeout'),
    ('probes (failed)', 'LatencyProbe calls the robot reported, and how many got no answer'),
    ('probe RTT', 'round trip of the answered probes, ms'),
)


def _ms(summary, keys):
    return ['%.2f' % (summary[k] * 1e3) if summary['n'] else '-' for k in keys]
