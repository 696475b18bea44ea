"""Unit tests import the ROS-free modules; no master, no build needed.

``src`` is appended (not prepended) so that a sourced devel space, which also provides
the generated messages, keeps precedence.
"""
import os
import sys

sys.path.append(os.path.join(os.path.dirname(__file__), '..', '..', 'src'))
