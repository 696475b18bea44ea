"""The manager's stores (no rospy): every robot's ranking from the probe samples
(``sample_rankings``, the paper) or from the views robots send (``view_rankings``)."""
