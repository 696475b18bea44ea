"""The fleet simulated on a virtual clock (no rospy): the package's own core objects
(every rule, the health table, the probe plan, the task flow, the server's work queue)
driven by a discrete-event loop, with links, servers' CPU and task arrivals modelled.

``events`` (the loop and the seeded random streams), ``network`` (links and connections),
``server`` and ``robot`` (the simulated nodes), ``model`` (what is measured of the testbed:
service times, middleware delays), ``run`` (one scenario, one variant, one seed),
``figures`` and ``stats`` (what a run gives and what many seeds give), ``league`` (every
scenario, variant and seed), ``generate`` (scenario files nobody wrote), ``from_bag``
(a recorded run's links as a scenario), ``cli`` (``rosrun server_select simulate``).
"""
