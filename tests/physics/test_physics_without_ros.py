"""The ROS-free physics suite runs where ROS is not installed.

A child pytest runs with an import hook that refuses every ROS module (as on a machine without
ROS 2): it collects all of tests/physics (so no test module, nor tests/conftest.py, imports ROS
at import time) and runs two physics files to the end.
"""
import os
import subprocess
import sys

_HERE = os.path.dirname(os.path.abspath(__file__))
_ROOT = os.path.dirname(os.path.dirname(_HERE))

# Installed with ROS 2 (Jazzy), never with the physics packages. ament_index_python is only a
# file lookup, but it comes with ROS too: the physics must not need it either.
_BLOCKER = r'''
import sys

BLOCKED = ("rclpy", "rcl_interfaces", "rcl_logging", "rmw", "rosidl", "rpyutils", "ament_index_python",
           "builtin_interfaces", "std_msgs", "geometry_msgs", "nav_msgs", "visualization_msgs",
           "rosgraph_msgs", "tug_msgs", "launch", "rosbag2_py")


class NoRos:
    @staticmethod
    def find_spec(name, path=None, target=None):
        if name.split(".")[0].startswith(BLOCKED):
            raise ModuleNotFoundError(f"No module named {name!r} (ROS blocked by the test)", name=name)
        return None


sys.meta_path.insert(0, NoRos)
import pytest  # noqa: E402

sys.exit(pytest.main(sys.argv[1:]))
'''


def _pytest_without_ros(*args):
    return subprocess.run([sys.executable, "-c", _BLOCKER, "-p", "no:cacheprovider", *args], cwd=_ROOT,
                          capture_output=True, text=True, timeout=600)


def test_physics_tests_import_no_ros():
    proc = _pytest_without_ros("--collect-only", "-q", "tests/physics")
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-4000:]
    assert "test_savitsky_table2.py::" in proc.stdout


def test_physics_tests_pass_without_ros():
    proc = _pytest_without_ros("-q", "tests/physics/test_savitsky_table2.py", "tests/physics/test_rope_files_schema.py")
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-4000:]
    assert " passed" in proc.stdout and "skipped" not in proc.stdout, proc.stdout[-2000:]


def test_blocker_blocks_rclpy():
    """The hook does what the two tests above rely on."""
    proc = subprocess.run([sys.executable, "-c", _BLOCKER.replace("sys.exit(pytest.main(sys.argv[1:]))",
                                                                  "import rclpy")],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode != 0 and "ROS blocked by the test" in proc.stderr, proc.stderr
