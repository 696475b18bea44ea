"""Per-robot run summary built from selection flags and task reports (no rospy)."""

import collections

from server_select.stats import summarize


class RunReport(object):
    """Accumulates what a run's topics say about each robot."""

    def __init__(self):
        self.flags = {}
        self.switches = collections.Counter()
        self.tasks = collections.defaultdict(list)

    def add_flag(self, robot_id, server_id, ranking, means):
        previous = self.flags.get(robot_id)
        if previous is not None and previous[0] != server_id:
            self.switches[robot_id] += 1
        self.flags[robot_id] = (server_id, list(ranking), list(means))

    def add_task(self, robot_id, ok, rtt, server_id, error):
        self.tasks[robot_id].append((ok, rtt, server_id, error))

    def robot_summary(self, robot_id):
        tasks = self.tasks.get(robot_id, [])
        selected, ranking, means = self.flags.get(robot_id, (None, [], []))
        errors = collections.Counter(t[3] for t in tasks if not t[0])
        return {
            'robot': robot_id,
            'selected': selected,
            'ranking': ranking,
            'mean_latency_ms': [m * 1e3 for m in means],
            'switches': self.switches[robot_id],
            'tasks': len(tasks),
            'ok': sum(1 for t in tasks if t[0]),
            'failed': sum(1 for t in tasks if not t[0]),
            'errors': dict(errors),
            'servers_used': sorted(set(t[2] for t in tasks if t[0])),
            'rtt': summarize([t[1] for t in tasks if t[0]]),
        }

    def summaries(self):
        return [self.robot_summary(r) for r in sorted(set(self.flags) | set(self.tasks))]

    def table(self):
        """A Markdown table, one row per robot."""
        lines = ['| robot | selected | ranking (mean probe RTT ms) | switches | tasks | ok | failed '
                 '| RTT median ms | RTT p95 ms | RTT p99 ms | RTT max ms |',
                 '|---|---|---|---|---|---|---|---|---|---|---|']
        for s in self.summaries():
            ranking = ', '.join('S%d %.2f' % (srv, ms)
                                for srv, ms in zip(s['ranking'], s['mean_latency_ms'])) or '-'
            rtt = s['rtt']
            cells = ['%.2f' % (rtt[k] * 1e3) if rtt['n'] else '-'
                     for k in ('median', 'p95', 'p99', 'max')]
            lines.append('| R%d | %s | %s | %d | %d | %d | %d | %s |' % (
                s['robot'], 'S%d' % s['selected'] if s['selected'] not in (None, -1) else 'none',
                ranking, s['switches'], s['tasks'], s['ok'], s['failed'], ' | '.join(cells)))
        return '\n'.join(lines)
