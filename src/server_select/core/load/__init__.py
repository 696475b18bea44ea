"""A server's load (no rospy): its bounded work queue and the load report a probe
answer carries (``work_queue``), and what robots announce they will send (``demand``).
"""
