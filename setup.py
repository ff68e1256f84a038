# The Python package attitude_planner (src/attitude_planner): catkin_python_setup() in
# CMakeLists.txt reads this, so that after sourcing the workspace `import attitude_planner` finds
# this package, its C++ extension (_core, built by CMake) and the generated msg/srv modules.
from setuptools import setup

from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["attitude_planner"], package_dir={"": "src"}))
