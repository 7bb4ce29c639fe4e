"""ROS-free numerics shared by the physics and analysis packages, each concept written once:
``rotations`` (REP-103 rotations and quaternions), ``integration`` (the classical Runge-Kutta
step), ``turning`` (least-squares circle fit and the IMO / ITTC turning measures), ``input_files`` (the
strict YAML reader of every ship, rope, cable and scenario file)."""
