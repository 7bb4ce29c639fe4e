"""Dead Fast DDS shared-memory files, left in /dev/shm by processes that were killed.

Fast DDS (2.14, Jazzy's) gives every participant a shared-memory port, /dev/shm/fastrtps_port<N>
plus a semaphore sem.fastrtps_port<N>_mutex, numbered from the domain and the participant index.
A process that dies without closing it (SIGKILL, OOM killer, power cut of a container) leaves
the files behind. The next participant that gets the same number opens the dead port, and
messages sent to it are lost: measured here, every later run on that domain stalled at step
0 -> 1 ("/tug/vessel stopped answering"), until the files were removed. `fastdds shm clean`
(Fast DDS's own tool) keeps these files, because it only judges files that have a lock file.

The test used here is the kernel's: a file that no live process has mapped, and that is older
than a second (a port is mapped within microseconds of its creation), is dead.
"""
from __future__ import annotations

import os
import re
import time
from typing import List, Set

SHM_DIR = "/dev/shm"
_FASTDDS_FILE = re.compile(r"^(sem\.)?fastrtps_")


def mapped_shm_files(shm_dir: str = SHM_DIR) -> Set[str]:
    """Base names of the files in shm_dir some live process has mapped. Processes whose maps
    cannot be read (other users', non-dumpable ones such as a container's init) are passed
    over: the files of other users cannot be removed anyway (/dev/shm is sticky)."""
    mapped_path = re.compile(r"\s" + re.escape(shm_dir.rstrip("/") + "/") + r"([^/\s]+)")
    names: Set[str] = set()
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/maps") as f:
                text = f.read()
        except OSError:
            continue  # ended meanwhile, or not readable
        names.update(mapped_path.findall(text))
    return names


def _owner_name(name: str) -> str:
    """The port or segment a file belongs to: fastrtps_port7661_el -> fastrtps_port7661,
    sem.fastrtps_port7661_mutex -> fastrtps_port7661."""
    if name.startswith("sem."):
        name = name[4:]
    for suffix in ("_mutex", "_el", "_sl"):
        if name.endswith(suffix):
            return name[: -len(suffix)]
    return name


def dead_fastdds_files(shm_dir: str = SHM_DIR, min_age: float = 1.0) -> List[str]:
    """Paths of Fast DDS shared-memory files whose port or segment no live process maps."""
    try:
        names = [n for n in os.listdir(shm_dir) if _FASTDDS_FILE.match(n)]
    except FileNotFoundError:
        return []
    if not names:
        return []
    mapped = {_owner_name(n) for n in mapped_shm_files(shm_dir) if _FASTDDS_FILE.match(n)}
    now = time.time()
    dead = []
    for name in names:
        path = os.path.join(shm_dir, name)
        try:
            young = now - os.stat(path).st_mtime < min_age
        except OSError:
            continue
        if not young and _owner_name(name) not in mapped:
            dead.append(path)
    return sorted(dead)


def remove_dead_fastdds_files(shm_dir: str = SHM_DIR, min_age: float = 1.0) -> List[str]:
    """Remove the dead files this user may remove; returns the removed paths."""
    removed = []
    for path in dead_fastdds_files(shm_dir, min_age):
        try:
            os.unlink(path)
            removed.append(path)
        except OSError:
            pass  # another user's file (/dev/shm is sticky), or gone meanwhile
    return removed
