"""The fleet profile's per-task rule (no rospy): ``least_latency``; ``estimates``, the one
load model every rule keeps and every robot's deadlines read; and ``balancer``, the state
every per-task rule is told (the league's peers build on it too)."""
