"""server_select: latency-based compute server selection for ROS robot fleets.

Modules without a ``_node`` suffix import no rospy and are tested without a master.
"""
