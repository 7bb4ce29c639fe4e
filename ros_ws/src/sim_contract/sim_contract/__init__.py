"""What describes a run, written once and imported downward (ROS-free): ``scenario`` (the
scenario format: schema, checks, the files it names), ``particulars`` (ship lengths, hull
dimensions, breaking loads: from a scenario or a recording), ``geo`` (units and geodesy at the
human edge: knots, compass degrees, WGS-84) and ``equipment`` (MMSI, UTC of bridge equipment)."""
