"""Task types built through the plug-in interface (:mod:`server_select.ros.plugins`)."""
