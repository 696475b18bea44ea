"""server_select: latency-based compute server selection for ROS robot fleets.

Sub-packages by audience: ``core`` (selection and task logic) and ``vision`` (images,
detection, search) import no rospy and are tested without a master; ``ros`` holds the
rospy adapters, ``nodes`` one class and ``main()`` per node; ``testbed`` and ``bench`` are
the evaluation and the benchmarks.
"""
