"""ROS 2 adapters: thin nodes around the same robot and centre objects the simulator drives
(:mod:`~mrexplore.preprocessing.agents`). Imported only by the ``mrexplore ros2`` commands and their tests:
``import mrexplore`` never imports rclpy. Installed with ``pip install -e ".[ros2]"`` (ROS 2 Jazzy's rclpy and
messages from PyPI), or use a sourced ROS 2 installation's rclpy."""
