"""Tests of the ROS side that need the catkin build (generated messages) but no master.

``src`` is appended (not prepended) so that the sourced devel space, which provides the
generated messages, keeps precedence.
"""
import os
import sys

sys.path.append(os.path.join(os.path.dirname(__file__), '..', '..', 'src'))
