"""The scenario format, ROS-free: ``scenario`` (one YAML file names everything a run needs:
schema, checks before any node starts, the files it names) and ``particulars`` (what a run's
topics do not carry: ship lengths, hull dimensions, breaking loads; from a scenario or from a
recording's metadata). Built on the contract (sim_contract) and the physics packages whose
files it checks."""
