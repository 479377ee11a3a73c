# Sourced by the scripts: the build folder and an environment free of pyenv's python3.
# ROS on Debian lives in /usr; /usr/bin must come before pyenv so that catkin finds catkin_pkg.
F3R_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
F3R_BUILD=${F3R_BUILD:-$F3R_ROOT/build}
F3R_WS=${F3R_WS:-$F3R_BUILD/ws}
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
export PYENV_VERSION=system
export ROS_HOME=$F3R_BUILD/ros_home
export ROS_LOG_DIR=$ROS_HOME/log
export ROS_HOSTNAME=localhost
