"""Issue 13 item 6: output and log paths are checked before anything starts; a recording is
never replaced without saying so; the log folder follows the recording's name."""
import subprocess

import pytest

from conftest import executable_path

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]


def run(*args):
    return subprocess.run([executable_path("scenario_runner", "run_scenario"), "seed000_free_fall_air.yaml",
                           "--duration", "0.1", "--quiet", *args], capture_output=True, text=True, timeout=100)


@pytest.mark.parametrize("output, message", [
    ("/dev/full", "is not a regular file"),
    ("/proc/x.mcap", "/proc/x.mcap"),
    ("/tmp", "is a folder"),
])
def test_unwritable_output_is_refused_before_start(tmp_path, ros_domain, output, message):
    proc = run("--output", output, "--log-dir", str(tmp_path / "logs"))
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
