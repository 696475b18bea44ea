"""The oracle node's flags in a simulation (no rospy): each robot of the ``oracle``
variant is told the truly nearest server of the scenario, as ``nodes/oracle.py`` tells it
on the testbed."""

from server_select.core.ranking.rank import NO_SERVER

PERIOD = 0.05        # the oracle node's update rate: 20 Hz


class OracleFlags(object):
    """Flags for ``robot`` (a core Robot), the scenario's robot ``scenario_id``: on each
    change of the scenario's ranking, and once a second."""

    def __init__(self, loop, scenario, scenario_id, robot):
        self.loop, self.scenario, self.scenario_id, self.robot = loop, scenario, scenario_id, robot
        self._flagged = None

    def start(self):
        now = self.loop.now()
        ranked, _ = self.scenario.ranking(self.scenario_id, now)
        servers = [s for _, s in ranked]
        if servers != self._flagged or int(now) != int(now - PERIOD):
            self._flagged = servers
            self.robot.on_flag(self.robot.robot_id, servers[0] if servers else NO_SERVER,
                               servers)
        self.loop.after(PERIOD, self.start)
