"""Files shipped with the package (config/, launch/), found the ROS way."""

import os

import rospkg


def package_file(*parts):
    """The path of ``parts`` inside this package's share folder (source or installed)."""
    return os.path.join(rospkg.RosPack().get_path('server_select'), *parts)
