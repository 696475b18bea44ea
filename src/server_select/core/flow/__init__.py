"""A task's life at the robot (no rospy): make, send, re-send, hedge, check and report
each task once (``task_flow``), attempt deadlines (``attempts``), the re-send budget
(``budget``), pending tasks and outcomes (``outcome``), the sort kernel (``sort_kernel``).
"""
