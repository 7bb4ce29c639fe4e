"""A stand-in for the part of ros2cli that is not on PyPI (scripts/ros2 dispatches to it):
``graph_verbs`` offers `ros2 topic list/info/echo/hz`, `ros2 node list` and `ros2 param
list/get/set` on rclpy, printing what ros2cli prints. Not simulator code: a user's tool."""
