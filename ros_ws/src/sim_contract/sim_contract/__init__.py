"""The contract of the simulator's nodes, written once and imported downward (ROS-free): each
node's parameter table (``node_params``), units and geodesy at the human edge (``geo``: knots,
compass degrees, WGS-84) and the identities of bridge equipment (``equipment``: MMSI, UTC)."""
