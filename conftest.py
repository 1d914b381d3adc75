"""pytest's collection from the repository root: the ROS 2 adapters import rclpy, which only the ``ros2``
extra installs (CI installs it, so nothing is left out there)."""

import importlib.util

collect_ignore_glob = [] if importlib.util.find_spec("rclpy") else ["src/mrexplore/ros2/*.py"]
