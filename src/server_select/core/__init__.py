"""The package's logic, free of rospy and of generated messages (``test_layout`` checks it):
what a node decides, unit-tested without a master. Nodes (``nodes/``) are thin wiring over
it through ``ros/``.

One sub-package per topic, each importing only those listed before it (``test_layout``
checks the direction and that there is no cycle):

- ``util``: waiting, processes, Markdown tables, summary statistics.
- ``config``: parameter parsers, graph names and the ids that stand for no server.
- ``trust``: fleet key files, seals (who may sign what) and the publisher check.
- ``load``: a server's work queue and load reports; what robots announce they send.
- ``ranking``: the paper profile's ranking: latency windows, the stable sort, the
  policies (mean, hysteresis), answered tasks as samples.
- ``rule``: the fleet profile's per-task rule, ``least_latency``, the one load model every
  rule keeps, and what every per-task rule is told.
- ``peers``: the league's peers, per-task balancers a user might put there instead.
- ``manager``: the manager's stores of every robot's ranking.
- ``flow``: a task's life at the robot: send, re-send, hedge, check, report once.
- ``fleet``: membership by leases, server groups.
- ``robot``: the robot whole, one object over its selection (which servers a task may go
  to, health, probe plan), load and flow, driven alike by the robot node and the simulator.
- ``settings``: the table of every node parameter (a module: it names every rule's choices).
- ``observe``: what a run did (summaries) and what ``top`` shows.
"""
