"""The workspace backbone (packages, interfaces, executables, isolation, set-up errors)."""
import os
import shutil
import subprocess

import pytest

from conftest import executable_path

PACKAGES = {"sim_math", "sim_contract", "tug_msgs", "tf2_msgs", "sim_plumbing", "ros2cli_standin", "tug_dynamics", "rope_model",
            "scenario_format", "recording", "scenario_runner", "live_view", "sea_environment", "bridge_instruments", "hull_contact", "studies"}


def test_colcon_lists_the_packages(repo_root):
    out = subprocess.run(["colcon", "--log-base", os.devnull, "list", "--names-only", "--base-paths", os.path.join(repo_root, "ros_ws", "src")],
                         capture_output=True, text=True, check=True).stdout.split()
    assert set(out) == PACKAGES


def _msg_files(repo_root):
    msg_dir = os.path.join(repo_root, "ros_ws", "src", "tug_msgs", "msg")
    return sorted(os.path.join(msg_dir, f) for f in os.listdir(msg_dir) if f.endswith(".msg"))


def test_every_tug_msgs_type_imports_and_round_trips(repo_root):
    import tug_msgs.msg
    from rclpy.serialization import deserialize_message, serialize_message
    files = _msg_files(repo_root)
    assert len(files) >= 9
    for path in files:
        name = os.path.basename(path)[:-4]
        cls = getattr(tug_msgs.msg, name)
        msg = cls()
        assert type(deserialize_message(serialize_message(msg), cls)) is cls


def test_every_field_is_documented(repo_root):
    """Each field or constant sits in a block (no blank line) that starts with a comment."""
    for path in _msg_files(repo_root):
        documented = False
        for line in open(path).read().splitlines():
            if not line.strip():
                documented = False
            elif line.lstrip().startswith("#"):
                documented = True
            else:
                assert documented, f"{os.path.basename(path)}: field '{line}' has no comment above it"


def test_node_executables_are_where_ros2_run_looks():
    for package, exe in [("tug_dynamics", "vessel_node"), ("rope_model", "rope_node"),
                         ("scenario_runner", "send_command")]:
        path = executable_path(package, exe)
        assert path.endswith(os.path.join("lib", package, exe))


@pytest.mark.timeout(60)
def test_ros2_run_stand_in_passes_ros_args(ros_domain):
    """`ros2 run` finds the installed executable and hands it --ros-args unchanged."""
    assert shutil.which("ros2")
    proc = subprocess.run(["ros2", "run", "tug_dynamics", "vessel_node", "--ros-args", "-r", "__ns:=/tug",
                           "-p", "ship_file:=no_such_ship.yaml"], capture_output=True, text=True, timeout=45)
    assert proc.returncode == 2
    assert "no_such_ship.yaml" in proc.stderr
    bad = subprocess.run(["ros2", "run", "tug_dynamics", "no_such_exe"], capture_output=True, text=True)
    assert bad.returncode == 1 and "vessel_node" in bad.stderr


def _toolbox(tmp_path, tools):
    """A PATH directory with only the named tools (symlinks to the real ones)."""
    box = tmp_path / "bin"
    box.mkdir()
    for tool in tools:
        real = shutil.which(tool, path="/usr/local/bin:/usr/bin:/bin")
        if real:
            os.symlink(real, box / tool)
    return str(box)


BASE_TOOLS = ["bash", "env", "sha256sum", "cut", "cat", "find", "sort", "xargs", "mkdir", "readlink", "ln", "sed",
              "grep", "tail", "rm", "dirname"]


@pytest.mark.parametrize("missing, expected", [
    ("python", "Python 3.11 not found"),
    ("cmake", "cmake not found"),
    ("cc", "C compiler 'cc' not found"),
])
def test_setup_names_what_to_install(tmp_path, repo_root, missing, expected):
    import sys
    tools = list(BASE_TOOLS) + ["cmake", "cc", "c++"]
    if missing != "python":
        tools.remove(missing)
    box = _toolbox(tmp_path, tools)
    if missing != "python":
        os.symlink(sys.base_prefix + "/bin/python3.11" if os.path.exists(sys.base_prefix + "/bin/python3.11")
                   else shutil.which("python3.11") or shutil.which("python3"), os.path.join(box, "python3"))
    env = {"HOME": str(tmp_path), "PATH": box}
    proc = subprocess.run([os.path.join(box, "bash"), os.path.join(repo_root, "scripts", "ensure_env.sh")],
                          env=env, capture_output=True, text=True, timeout=60)
    assert proc.returncode != 0
    assert expected in proc.stderr and "Install it" in proc.stderr, proc.stderr
