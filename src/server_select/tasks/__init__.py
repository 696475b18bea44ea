"""Task types built through the plug-in interface (:mod:`server_select.ros.plugins`), and
the ones a node's parameters ask for (:mod:`server_select.tasks.kinds`). Above ``ros/``:
``ros/`` imports nothing of this package."""
