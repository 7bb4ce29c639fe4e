"""Output and log paths are checked before anything starts; a recording is
never replaced without saying so; the log folder follows the recording's name."""
import subprocess

import pytest

from conftest import executable_path

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]


ARGS = ["seed000_free_fall_air.yaml", "--duration", "0.1", "--quiet", "--layout", "processes"]   # node logs


def run(*args):
    return subprocess.run([executable_path("scenario_runner", "run_scenario"), *ARGS, *args], capture_output=True,
                          text=True, timeout=100)


@pytest.mark.parametrize("output, message", [
    ("/dev/full", "is not a regular file"),
    ("/proc/x.mcap", "/proc/x.mcap"),
    ("/tmp", "is a folder"),
])
def test_unwritable_output_is_refused_before_start(tmp_path, ros_domain, run_in_process, output, message):
    """Refused by the runner's own checks before it starts anything: run in this process (the
    exit status 2 through the executable: test_malformed_inputs)."""
    proc = run_in_process("run_scenario", *ARGS, "--output", output, "--log-dir", tmp_path / "logs")
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert message in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "logs").exists()


def test_logs_follow_the_output_name_and_replacing_is_said(tmp_path, ros_domain):
    first = run("--output", str(tmp_path / "a.mcap"))
    second = run("--output", str(tmp_path / "b.mcap"))
    assert first.returncode == 0 and second.returncode == 0, first.stderr + second.stderr
    assert (tmp_path / "a_logs" / "rope_rope.log").exists() and (tmp_path / "b_logs" / "rope_rope.log").exists()
    assert "replacing" not in first.stderr
    again = run("--output", str(tmp_path / "a.mcap"))
    assert again.returncode == 0
    assert f"replacing the existing recording {tmp_path / 'a.mcap'}" in again.stderr


@pytest.fixture
def small_disk(tmp_path):
    """A 1 MiB file system (tmpfs; the tests run as root, as CI does): the 5 kn straight tow of the
    towing-rope paper fills it after some 12 s of simulated time (about 80 kB/s of recording)."""
    mount = tmp_path / "small_disk"
    mount.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(mount)], check=True)
    yield mount
    subprocess.run(["umount", "-l", str(mount)], check=False)


def test_a_full_disk_stops_the_run_and_leaves_a_file_the_mcap_library_reads(tmp_path, ros_domain, small_disk):
    import re
    from mcap.reader import make_reader
    from recording.mcap_io import McapFile
    out = small_disk / "tow.mcap"
    proc = subprocess.run([executable_path("scenario_runner", "run_scenario"), "seed000_straight_tow_5kn.yaml",
                           "--duration", "60", "--quiet", "--output", str(out), "--log-dir", str(tmp_path / "logs")],
                          capture_output=True, text=True, timeout=200)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    assert f"writing {out} failed" in proc.stderr and "No space left on device" in proc.stderr, proc.stderr
    said = re.search(r"ends readably where the write failed: (\d+) messages up to t = ([\d.]+) s", proc.stderr)
    assert said, proc.stderr
    # the mcap library (not this project's reader) reads the file to its end, no error
    times = []
    with open(out, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(log_time_order=False):
            times.append(message.log_time * 1e-9)
    assert len(times) == int(said.group(1)) > 1000
    assert 1.0 < max(times) < 60.0 and max(times) == pytest.approx(float(said.group(2)), abs=0.01)
    assert McapFile(str(out)).scan().message_count == len(times)  # and it is the whole of it
    assert sorted(p.name for p in small_disk.iterdir()) == ["tow.mcap"]  # the reserve file is gone
