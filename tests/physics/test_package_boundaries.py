"""One home for the shared node plumbing; physics packages stay free of ROS.

Reads the sources (ast, no import), so it holds whatever is installed."""
import ast
import os

import pytest

SRC = os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src")
ROS_MODULES = {"rclpy", "rcl_interfaces", "builtin_interfaces", "std_msgs", "geometry_msgs", "nav_msgs",
               "visualization_msgs", "rosgraph_msgs", "tug_msgs", "tf2_msgs", "sim_plumbing"}  # ament_index_python (a file lookup) is allowed
# modules of a physics package that are allowed to be ROS shells (the nodes and their codecs)
NODE_MODULES = {"vessel_node.py", "rope_node.py", "state_cdr.py", "contact_node.py"}


def _imports(path):
    tree = ast.parse(open(path).read(), path)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.module.split(".")[0]


def _modules(package):
    root = os.path.join(SRC, package, package)
    return sorted(os.path.join(root, f) for f in os.listdir(root) if f.endswith(".py"))


def test_rope_model_imports_no_vessel_code():
    offenders = [(os.path.basename(p), m) for p in _modules("rope_model") for m in _imports(p)
                 if m in ("tug_dynamics", "scenario_runner")]
    assert offenders == []


def test_plumbing_imports_no_model_package():
    offenders = [(os.path.basename(p), m) for p in _modules("sim_plumbing") for m in _imports(p)
                 if m in ("tug_dynamics", "rope_model", "scenario_runner")]
    assert offenders == []


@pytest.mark.parametrize("package", ["tug_dynamics", "rope_model", "sea_environment", "sim_math", "hull_contact"])
def test_physics_modules_import_no_ros(package):
    offenders = [(os.path.basename(p), m) for p in _modules(package) if os.path.basename(p) not in NODE_MODULES
                 for m in _imports(p) if m in ROS_MODULES]
    assert offenders == []
