"""What one simulated run of one variant gives: the league's columns (no rospy).

Tasks count from their send time within the measured part (``measure_from`` to the end);
a task still out at the end is left out (the run's end cut it off, as the testbed's
analysis leaves it out). A failed task counts at the task timeout in the mean and p99.
Switches are changes of the server a robot's tasks were first sent to, per minute per
robot; the reaction is, for each change of a robot's nearest server (the oracle's), the
time from the change to the robot's first task sent there (median over the changes).
"""

import collections

from server_select.core.observe.summary import switch_count
from server_select.core.util.stats import percentile

Figures = collections.namedtuple(
    'Figures', 'tasks mean p99 failed switches reaction extra probes goodput wanted')
Figures.__doc__ = """Per run and variant: tasks, mean and p99 round trip (s, a failure at
the timeout), failed tasks, switches per minute per robot, reaction (s, None: no change),
extra sends per task (re-sends, hedges, copies), probes per second per robot, answered
tasks per second, and the share of the servers' finished work that a robot still wanted
(None: no work)."""


def _change_times(scenario, robot, step):
    """The times from which a robot's nearest server can differ: its links' events and
    ramps (every ``step`` s along one), and the servers' hangs, starts, stops and work."""
    host = scenario.host_for('robot', robot).name
    times = set()
    for pair, profile in scenario.links.items():
        if host in pair:
            times.update(profile.times)
            for ramp in profile.ramps:
                if ramp is not None:
                    times.update(ramp[0] + k * step
                                 for k in range(int((ramp[1] - ramp[0]) / step) + 1))
    for server in scenario.of_role('server'):
        times.update([server.start] + ([server.stop] if server.stop is not None else []))
        times.update(t for span in server.hang for t in span)
        times.update(at for at, _ in server.work)
    return sorted(times)


def _reaction(sim, robots, by_robot, step=0.1):
    delays = []
    for robot in robots:
        sends = sorted((o.stamp, o.server_id) for o in by_robot[robot.id])
        last = sim.scenario.nearest_server(robot.scenario_id, sim.measure_from)
        for t in _change_times(sim.scenario, robot.scenario_id, step):
            if not sim.measure_from < t < sim.scenario.duration:
                continue
            nearest = sim.scenario.nearest_server(robot.scenario_id, t)
            if nearest != last and nearest >= 0:
                first = next((s for s, server in sends if s >= t and server == nearest), None)
                if first is not None:
                    delays.append(first - t)
            last = nearest
    return percentile(sorted(delays), 50) if delays else None


def figures(sim, variant):
    """The :class:`Figures` of ``variant`` in ``sim`` (a finished Simulation)."""
    robots = [r for r in sim.robots if sim.variant_of[r.id] == variant]
    start, end = sim.measure_from, sim.scenario.duration
    by_robot = collections.defaultdict(list)
    for record in sim.records:
        if record.variant == variant and start <= record.outcome.stamp <= end:
            by_robot[record.robot].append(record.outcome)
    outcomes = [o for robot in robots for o in by_robot[robot.id]]
    times = sorted(o.rtt if o.ok else sim.timeout for o in outcomes)
    switches = 0
    for robot in robots:
        mine = sorted(by_robot[robot.id], key=lambda o: o.stamp)
        switches += switch_count([o.server_id for o in mine], [o.kind for o in mine])
    minutes = (end - start) / 60.0
    flows = [s.flow for r in robots for s in r.robot.streams]
    sent = sum(f.sent for f in flows)
    extra = sum(f.resent + f.hedged + f.replicated for f in flows)
    answers = sim.answers[variant]
    done = answers[True] + answers[False]
    return Figures(
        len(outcomes), sum(times) / len(times) if times else None,
        percentile(times, 99) if times else None, sum(1 for o in outcomes if not o.ok),
        switches / minutes / max(1, len(robots)), _reaction(sim, robots, by_robot),
        extra / float(sent) if sent else 0.0,
        sum(r.robot.probes for r in robots) / end / max(1, len(robots)),
        sum(1 for o in outcomes if o.ok and o.rtt <= sim.timeout) / (end - start),
        answers[True] / float(done) if done else None)
