"""Configuration below every topic (no rospy): parameter parsers and ``ParamError``
(``params``), graph names and the ids that stand for no server (``names``). The table of
parameters is :mod:`server_select.core.settings`, above the topics whose choices it names.
"""
