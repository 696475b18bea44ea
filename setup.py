# Installed by catkin_python_setup(); do not run directly.
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(
    packages=['server_select', 'server_select.core', 'server_select.vision', 'server_select.ros',
              'server_select.nodes', 'server_select.testbed', 'server_select.bench',
              'server_select.tasks'],
    package_dir={'': 'src'},
))
