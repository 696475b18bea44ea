"""The paper profile's ranking (no rospy): latency windows per (robot, server) pair
(``window``), the ranking by a window's statistic (``rank``), the policies that choose from
a ranking (``policy``: mean, hysteresis, and the names of the per-task rules), and answered
tasks as samples (``passive``)."""
