# Installed by catkin_python_setup(); do not run directly.
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(
    packages=['server_select', 'server_select.core', 'server_select.core.config',
              'server_select.core.util', 'server_select.core.trust',
              'server_select.core.selection', 'server_select.core.load',
              'server_select.core.flow', 'server_select.core.fleet', 'server_select.core.observe',
              'server_select.vision', 'server_select.ros',
              'server_select.nodes', 'server_select.testbed', 'server_select.bench',
              'server_select.tasks'],
    package_dir={'': 'src'},
))
