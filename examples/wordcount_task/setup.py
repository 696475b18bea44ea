# The plug-in's Python package, installed by catkin (catkin_python_setup), never by hand.
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=['wordcount_task'], package_dir={'': 'src'}))
