"""ROS-free environment models: wind, current, depth and waves."""
