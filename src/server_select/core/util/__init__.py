"""Utilities every layer may use (no rospy): waiting for a condition and stopping
processes (``procs``), Markdown tables (``tables``), summary statistics (``stats``).
"""
