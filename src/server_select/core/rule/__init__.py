"""The fleet profile's per-task rule (no rospy): ``least_latency``, and ``balancer``, the
state every per-task rule is told (the league's peers build on it too)."""
