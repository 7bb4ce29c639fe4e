"""Test-suite wide checks: the suite runs inside the project environment (./test.sh).

Imports nothing of ROS: tests/physics runs where the physics packages are importable and ROS
is not installed (tests/physics/test_physics_without_ros.py proves it). The ROS modules are
required only when the run includes tests/ros.
"""
import importlib.util
import os

import pytest

_TESTS = os.path.dirname(os.path.abspath(__file__))
_ROS_TESTS = os.path.join(_TESTS, "ros")
_SRC = os.path.join(os.path.dirname(_TESTS), "ros_ws", "src")
_PHYSICS = ("tug_dynamics", "rope_model")
_ROS = ("rclpy", "tug_msgs")


def _missing(modules):
    out = []
    for m in modules:
        try:
            found = importlib.util.find_spec(m) is not None
        except ImportError:  # a parent package is missing, or an import hook refuses it
            found = False
        if not found:
            out.append(m)
    return out


def _includes_ros_tests(config) -> bool:
    """True when a path the run was given is tests/ros, lies inside it, or contains it."""
    args = [a for a in config.args if not a.startswith("-")] or [config.rootpath / p for p in
                                                                 config.getini("testpaths")]
    for arg in args:
        path = os.path.abspath(os.path.join(str(config.invocation_params.dir), str(arg).split("::")[0]))
        if os.path.commonpath([path, _ROS_TESTS]) in (path, _ROS_TESTS):
            return True
    return False


def pytest_sessionstart(session):
    missing = _missing(_PHYSICS)
    if _includes_ros_tests(session.config):
        missing += _missing(_ROS)
    if missing:
        python_packages = sorted(d for d in os.listdir(_SRC) if os.path.isdir(os.path.join(_SRC, d, d)))
        raise pytest.UsageError(
            f"modules {missing} not importable: run the suite with ./test.sh (it builds the workspace and "
            "sources ros_ws/install/setup.bash), or source scripts/ensure_env.sh first. The ROS-free "
            "physics tests alone need only the Python packages' sources on the path: PYTHONPATH="
            + ":".join(f"ros_ws/src/{d}" for d in python_packages) + " pytest tests/physics")


@pytest.fixture(scope="session")
def repo_root():
    return os.environ.get("TUGSIM_ROOT") or os.path.dirname(_TESTS)


# Test files without module fixtures whose tests spread over the workers one by one (their library
# runs are shared across workers through a file-locked cache: test_startup_loads._recorded).
_SPREAD = {"test_scenarios.py", "test_startup_loads.py", "test_environment_runs.py"}


@pytest.hookimpl(tryfirst=True)   # before pytest-xdist's own, which turns the marker into the group
def pytest_collection_modifyitems(config, items):
    """With pytest-xdist (--dist loadgroup), a test file's tests go to one worker together (its
    module fixtures, e.g. a recording several tests read, are made once), except the files of
    long library runs, whose tests spread one by one; the files themselves spread over the workers."""
    for item in items:
        if item.path.name not in _SPREAD:
            item.add_marker(pytest.mark.xdist_group(item.path.name))
    # the long runs first, the quick physics last: the workers end together instead of one of them
    # finishing a long library run alone (a stable sort: each file keeps its order)
    items.sort(key=lambda item: 0 if item.path.name in _SPREAD else 1 if _ROS_TESTS in str(item.path) else 2)


def pytest_collection_finish(session):
    """pytest-xdist's loadgroup keeps a group on one worker by a suffix it writes into each test's
    node id; if the pytest in use ignores it (pytest 9.2 with xdist 3.8) every file's module
    fixtures would be made on both workers, silently: refuse to run instead."""
    if not getattr(session.config.option, "loadgroup", False):   # no xdist (e.g. -p no:xdist), or no groups
        return
    lost = [item.nodeid for item in session.items
            if item.get_closest_marker("xdist_group") and "@" not in item.nodeid.rsplit("]", 1)[-1]]
    if lost:
        raise pytest.UsageError(f"pytest-xdist's --dist loadgroup did not group {len(lost)} tests (e.g. {lost[0]}): "
                                "this pytest and pytest-xdist do not work together (requirements.in pins them)")
