"""The Fast DDS profile of the simulator's processes: config/fastdds_discovery.xml (a participant
announces itself every 0.5 s, so that the nodes of a run find each other within a fraction of a
second instead of up to 3 s). No rclpy import: set before the process's first participant."""
from __future__ import annotations

import os
from typing import Optional

from sim_math.data_files import package_data_dir

# Fast DDS 2.x reads the profile file named here when the process's first participant is made.
DDS_PROFILE_VARIABLE = "FASTRTPS_DEFAULT_PROFILES_FILE"
PROFILE_FILE = "fastdds_discovery.xml"


def use_discovery_profile() -> Optional[str]:
    """Point Fast DDS at the simulator's profile unless a profile is named already (a user's, or
    scripts/fastdds_lan.xml for several PCs: kept). The profile in effect, or None."""
    if not os.environ.get(DDS_PROFILE_VARIABLE):
        path = os.path.join(package_data_dir("sim_plumbing", "config"), PROFILE_FILE)
        if os.path.isfile(path):
            os.environ[DDS_PROFILE_VARIABLE] = path
    return os.environ.get(DDS_PROFILE_VARIABLE) or None
