"""mrexplore's ROS 2 nodes as a ROS package: ``ros2 run mrexplore_ros robot`` and ``ros2 run mrexplore_ros
centre`` are ``mrexplore ros2 robot`` and ``mrexplore ros2 centre``."""
