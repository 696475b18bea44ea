"""The robot as one object without ROS (:class:`~server_select.core.robot.robot.Robot`):
what the robot node runs on rospy and the simulator runs on its virtual clock."""
