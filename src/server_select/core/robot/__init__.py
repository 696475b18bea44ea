"""The robot as one object without ROS (:class:`~server_select.core.robot.robot.Robot`):
what the robot node runs on rospy and the simulator runs on its virtual clock. Its parts:
which servers a task may go to (``selection``, built from parameters by
``selection_params``), its health table (``health``), its probe plan and rounds
(``probe_plan``, ``probes``, ``answer_time``), its task streams (``stream``), what its
deadlines read of its rule's estimates and its probes announce (``robot_load``), its live
tuning (``tuning``) and the parameters it refuses (``refusals``)."""
