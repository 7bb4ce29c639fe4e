"""A run's recording and what reads it back: ``recorder`` (writes the MCAP file as rosbag2's MCAP
storage plugin does), ``mcap_io`` (tolerant reading of cut or damaged files, shared by the two
tools), ``replay`` (republishes a recording with its timing and /clock) and ``analysis``
(figures, a summary and the IMO trial measures of a recording)."""
