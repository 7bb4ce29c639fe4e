"""A run's recording and what reads it back: ``recorder`` (writes the MCAP file as rosbag2's MCAP
storage plugin does), ``mcap_io`` (tolerant reading of cut or damaged files, shared by the two
tools), ``replay`` (republishes a recording with its timing and /clock) and ``analysis`` (the
``analyze`` command: figures, a summary and the IMO trial measures of a recording) with its parts
``recorded_run`` (a recording read into arrays), ``measures`` (the numbers), ``figures``
(matplotlib) and ``summary_files`` (JSON and CSV)."""
