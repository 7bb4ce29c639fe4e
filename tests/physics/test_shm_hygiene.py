"""sim_plumbing.shm_hygiene: Fast DDS shared-memory files of dead processes are found and
removed; a file some live process maps, or one just created, is kept."""
import mmap
import os
import subprocess
import sys
import time

from sim_plumbing import shm_hygiene


def _file(path, size=4096, age=0.0):
    with open(path, "wb") as f:
        f.write(b"\0" * size)
    if age:
        t = time.time() - age
        os.utime(path, (t, t))
    return str(path)


def test_dead_port_and_segment_files_are_removed_live_ones_kept(tmp_path):
    d = str(tmp_path)
    dead = [_file(tmp_path / n, age=60) for n in ("fastrtps_port7663", "sem.fastrtps_port7663_mutex",
                                                  "fastrtps_0123456789abcdef", "fastrtps_0123456789abcdef_el")]
    live = [_file(tmp_path / n, age=60) for n in ("fastrtps_port7665", "fastrtps_port7665_el",
                                                  "sem.fastrtps_port7665_mutex")]
    young = _file(tmp_path / "fastrtps_port7667")
    other = _file(tmp_path / "not_dds_file", age=60)
    # another process maps the live port, as a Fast DDS participant does
    holder = subprocess.Popen([sys.executable, "-c", (
        "import mmap, sys, time\n"
        f"f = open({live[0]!r}, 'r+b'); m = mmap.mmap(f.fileno(), 0)\n"
        "print('mapped', flush=True); time.sleep(60)")], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "mapped"
        assert shm_hygiene.dead_fastdds_files(d) == sorted(dead)
        assert sorted(shm_hygiene.remove_dead_fastdds_files(d)) == sorted(dead)
        assert sorted(os.listdir(d)) == sorted(os.path.basename(p) for p in live + [young, other])
    finally:
        holder.kill()
        holder.wait()
    # its holder gone (and the file old enough), the port is dead too
    assert sorted(shm_hygiene.remove_dead_fastdds_files(d)) == sorted(live)
    assert sorted(os.listdir(d)) == ["fastrtps_port7667", "not_dds_file"]


def test_own_mapping_counts_as_live(tmp_path):
    path = _file(tmp_path / "fastrtps_port7001", age=60)
    with open(path, "r+b") as f, mmap.mmap(f.fileno(), 0):
        assert shm_hygiene.dead_fastdds_files(str(tmp_path)) == []
    assert shm_hygiene.dead_fastdds_files(str(tmp_path)) == [path]
