"""What the test suites share (``setup.cfg`` puts ``test/`` on pytest's path; a rostest
node finds it beside its script):

- :mod:`support.clock`: a clock the ROS-free tests move by hand (no rospy);
- :mod:`support.record`: a recorder of a fleet's topics for the rostest nodes, and the
  first task's retries until the fleet is wired;
- :mod:`support.fleet`: a demo fleet under roslaunch with its nodes' pids, killed and
  restarted by the fault tests, and a recorder of its reports, flags and log lines.

Roscores on a free port, node pids from a node's own XML-RPC API and testbed prefixes
are the package's (``server_select.bench.harness``, ``server_select.ros.graph``,
``server_select.testbed.traces.own_prefix``): benchmarks use them too.
"""
