"""ROS-free environment models (wind; depth and currents to follow)."""
