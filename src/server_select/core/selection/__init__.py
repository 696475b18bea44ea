"""How a robot's server is chosen (no rospy): latency windows (``window``), the
paper's ranking (``rank``) and the manager's rankings of every robot (``fleet_rankings``,
``robot_views``), policies (``policy``), the per-task rules, ``least_latency`` and the peers
(``least_latency``, ``balancers``), which servers a task may go to (``candidates``), when to
probe (``probing``), answered tasks as samples (``passive``), a robot's own health table
(``health``).
"""
