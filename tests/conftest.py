"""Test-suite wide checks: the suite runs inside the project environment (./test.sh)."""
import importlib.util
import os

import pytest

_NEEDED = ("rclpy", "tug_msgs", "tug_dynamics", "rope_model", "scenario_runner")


def pytest_sessionstart(session):
    missing = [m for m in _NEEDED if importlib.util.find_spec(m) is None]
    if missing:
        raise pytest.UsageError(
            f"modules {missing} not importable: run the suite with ./test.sh (it builds the workspace and "
            "sources ros_ws/install/setup.bash), or source scripts/ensure_env.sh first.")


@pytest.fixture(scope="session")
def repo_root():
    return os.environ.get("TUGSIM_ROOT") or os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
