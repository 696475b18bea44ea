"""Trust (no rospy): fleet key files and role keys (``keys``), signed messages and
the table of which role may sign what (``seal``), which node a message must come from
(``senders``).
"""
