"""One home for the shared node plumbing; physics packages stay free of ROS.

Reads the sources (ast, no import), so it holds whatever is installed."""
import ast
import os

import pytest

SRC = os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src")
ROS_MODULES = {"rclpy", "rcl_interfaces", "builtin_interfaces", "std_msgs", "geometry_msgs", "nav_msgs",
               "visualization_msgs", "rosgraph_msgs", "tug_msgs", "tf2_msgs", "sim_plumbing"}  # ament_index_python (a file lookup) is allowed
# modules of a physics package that are allowed to be ROS shells (the nodes and their codecs)
NODE_MODULES = {"vessel_node.py", "rope_node.py", "state_cdr.py", "contact_node.py", "interaction_node.py"}


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


# The packages in layers, lowest first: a package imports only from lower layers (its own modules
# aside). The nodes' contract (sim_contract) stands under every node; the scenario format stands
# on the physics whose files it checks and under everything that describes or drives a run.
LAYERS = [
    {"sim_math", "sea_environment"},                # numerics, the sea (ROS-free)
    {"sim_contract"},                               # the nodes' contract: parameter tables, units (ROS-free)
    {"sim_plumbing", "ros2cli_standin"},            # the step protocol, CDR, a node's main(); ros2 verbs
    {"tug_dynamics", "rope_model"},                 # vessel and rope models and their nodes
    {"hull_contact"},                               # contact between hulls (knows both)
    {"scenario_format"},                            # the scenario format, a run's particulars (ROS-free)
    {"bridge_instruments", "live_view", "recording"},  # the human edge; a run's recording, replay, analysis
    {"scenario_runner"},                            # runs a scenario
    {"studies"},                                    # runs many: sweeps and seeds on Dask
]
_LAYER = {p: i for i, layer in enumerate(LAYERS) for p in layer}


def _python_packages():
    return sorted(d for d in os.listdir(SRC) if os.path.isfile(os.path.join(SRC, d, d, "__init__.py")))


def _module_imports(path, package):
    """(imported first-party module, line) of a file: every import, also inside functions."""
    tree = ast.parse(open(path).read(), path)
    for node in ast.walk(tree):
        names = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                names = [f"{package}.{node.module}" if node.module else package]
            elif node.module:
                names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        for name in names:
            if name.split(".")[0] in _LAYER:
                yield name, node.lineno


def test_every_package_has_a_layer():
    assert set(_python_packages()) == set(_LAYER)


def test_packages_import_only_downward():
    upward = []
    for package in _python_packages():
        for path in _modules(package):
            for name, line in _module_imports(path, package):
                other = name.split(".")[0]
                if other != package and _LAYER[other] >= _LAYER[package]:
                    upward.append(f"{package}/{os.path.basename(path)}:{line} imports {name}")
    assert upward == []


def test_no_module_imports_itself_back():
    """No cycle of modules (strongly connected component of the import graph, function-level
    imports included)."""
    modules = {f"{p}.{os.path.basename(f)[:-3]}": (f, p) for p in _python_packages() for f in _modules(p)}
    graph = {m: set() for m in modules}
    for m, (path, package) in modules.items():
        for name, _ in _module_imports(path, package):
            while name and name not in modules:
                name = name.rpartition(".")[0]
            if name and name != m and not name.endswith(".__init__"):
                graph[m].add(name)
    # Tarjan's strongly connected components
    index, low, stack, on, cycles, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    assert cycles == []


@pytest.mark.parametrize("package", ["sim_contract", "scenario_format"])
def test_the_contract_and_the_scenario_format_are_ros_free(package):
    offenders = [(os.path.basename(p), m) for p in _modules(package) for m in _imports(p)
                 if m in ROS_MODULES | {"ament_index_python"}]
    assert offenders == []
