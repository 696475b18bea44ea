"""What a run did and what the fleet does now (no rospy): per-robot run summaries
(``summary``), the state ``rosrun server_select top`` shows (``fleet_view``).
"""
