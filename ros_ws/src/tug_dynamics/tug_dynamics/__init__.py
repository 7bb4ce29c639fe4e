"""Vessel models of the towing simulator (ROS-free physics) and the vessel node."""
