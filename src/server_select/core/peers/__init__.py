"""The league's peers (no rospy): the per-task balancers a user would put in front of
servers instead of the fleet's rule, run beside it by ``make league`` and the testbed."""
