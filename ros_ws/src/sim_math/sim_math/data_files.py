"""The one lookup of the data files the packages ship (ships/, ropes/, scenarios/), ROS-free.

A package's data directory is its source tree's (the colcon build installs it with
--symlink-install, so the share directory holds links to the same files), else the installed
share/<package>/<subdir> found through ament_index when ROS is there.

    package_data_dir("tug_dynamics", "ships")                 # .../tug_dynamics/ships
    resolve("tug_dynamics", "ships", "harbour_tug.yaml")      # a bare name: in that directory
    resolve("rope_model", "ropes", "table1.yaml", relative_to="/x/run.yaml")  # /x/table1.yaml first
"""
from __future__ import annotations

import os
from typing import Optional

_SRC = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))  # ros_ws/src


def package_data_dir(package: str, subdir: str) -> str:
    """<package>/<subdir> of the source tree if it is there, else share/<package>/<subdir>."""
    source = os.path.join(_SRC, package, subdir)
    if os.path.isdir(source):
        return source
    try:
        from ament_index_python.packages import get_package_share_directory  # optional: ROS installs
        return os.path.join(get_package_share_directory(package), subdir)
    except Exception:  # noqa: BLE001 - no ROS, or not installed: the source layout (named in errors)
        return source


def resolve(package: str, subdir: str, name: str, relative_to: Optional[str] = None) -> str:
    """Where a data file a user names is: an absolute path, or a path that exists, as given; a
    name beside the file `relative_to` (a scenario naming its ship files) if one is there; else
    a name in the package's data directory (on the command line, without relative_to, ".yaml"
    is added to a bare name that lacks it)."""
    if os.path.isabs(name):
        return name
    if relative_to is not None:
        local = os.path.join(os.path.dirname(os.path.abspath(relative_to)), name)
        if os.path.isfile(local):
            return local
    elif os.sep in name or os.path.exists(name):
        return name
    candidate = os.path.join(package_data_dir(package, subdir), name)
    if relative_to is None and not candidate.endswith((".yaml", ".yml")) and not os.path.exists(candidate):
        candidate += ".yaml"
    return candidate


def shipped_name(package: str, subdir: str, path: str) -> str:
    """A path resolve() gave, as the name another installation resolves to its own copy: the bare
    file name when the file is one the package ships (in its data directory), else the path as
    given (a user's own file: the other machine needs it at that path)."""
    if os.path.isabs(path) and os.path.dirname(os.path.realpath(path)) == os.path.realpath(
            package_data_dir(package, subdir)):
        return os.path.basename(path)
    return path
