"""Plumbing shared by every node of the simulator: the lockstep step protocol (stepping), the
per-step messages as CDR bytes (cdr), the recorder's feed (record_feed) and the common ROS
pieces (ros_common: frames, QoS, parameters, executors, a node's main()).

No physics here, and no physics package imports another: vessels (tug_dynamics), ropes
(rope_model) and the runner (scenario_runner) all build on this package.
"""
