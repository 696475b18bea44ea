"""Fleet membership (no rospy): servers as members by leases (``leases``), server
groups for many servers (``groups``).
"""
