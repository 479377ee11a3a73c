# The Python module over the core (import flex3rpr), for catkin_python_setup: the package in src/
# shares its name with the generated messages (flex3rpr.msg, flex3rpr.srv), as ROS packages do.
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["flex3rpr"], package_dir={"": "src"}))
