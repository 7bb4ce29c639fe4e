"""Each node declares exactly its parameter table (sim_contract.node_params): a vessel, a rope,
a contact and an interaction node, started as processes as `ros2 run` starts them, are asked through the
standard rcl_interfaces services (as `ros2 param list / describe / get` ask) for their
parameters; the names, types, ranges and defaults are the table's, and only the live ones
change while running."""
import pytest

from conftest import spin_until

pytestmark = [pytest.mark.ros, pytest.mark.timeout(180)]

ROS_BUILT_INS = {"use_sim_time", "start_type_description_service"}  # every rclpy node has them
# (executable, its namespace and node name, the parameters the test gives: not compared with defaults)
NODES = [
    ("tug_dynamics", "vessel_node", "/tug/vessel", {"ship_file": "harbour_tug.yaml"}),
    ("rope_model", "rope_node", "/towline/rope", {"end_a_position": [0.0, 0.0, 0.0],
                                                  "end_b_position": [60.0, 0.0, 0.0]}),
    ("hull_contact", "contact_node", "/push/contact", {
        "fender_vessel": "tug", "hull_vessel": "ship", "fender_ship_file": "asd_tug.yaml",
        "hull_ship_file": "s175_003.yaml"}),
    ("hull_contact", "interaction_node", "/interactions/interaction", {
        "vessels": ["ship", "tug"], "ship_files": ["s175_003.yaml", "asd_tug.yaml"], "pairs": ["pass=ship,tug"]}),
    ("scenario_runner", "autopilot", "/pilot/autopilot", {"vessel": "tug"}),
    ("bridge_instruments", "nmea_out", "/bridge/nmea_out", {"vessels": ["tug"]}),
    ("live_view", "live_view", "/viewer/live_view", {"port": 0, "http_port": -1}),
]
STEPPED = ("vessel_node", "rope_node", "contact_node", "interaction_node", "autopilot")  # fixed parameters refused while running


def _ros_args(name, given):
    ns, node = name.rsplit("/", 1)
    args = ["--ros-args", "-r", f"__ns:={ns}", "-r", f"__node:={node}"]
    for key, value in given.items():
        text = "[" + ",".join(repr(v) for v in value) + "]" if isinstance(value, list) else str(value)
        args += ["-p", f"{key}:={text}"]
    return args


def _call(node, request, what):
    """request() -> a future, answered within 20 s. Asked again every 5 s: wait_for_services
    sees the service's request topic, not whether the server's response writer has matched this
    client's reader yet; a reply sent before that is lost ("failed to send response (timeout)"
    from rmw_fastrtps), so the first request of a fresh client can go unanswered."""
    for _ in range(4):
        future = request()
        if spin_until(node, future.done, 5.0):
            return future.result()
    pytest.fail(f"{what}: no answer in 20 s (asked 4 times)")


@pytest.mark.parametrize("package,executable,name,given", NODES, ids=[n[1] for n in NODES])
def test_a_running_node_declares_exactly_its_table(package, executable, name, given, start_node, rclpy_context):
    from rcl_interfaces.msg import ParameterType
    from rclpy.node import Node
    from rclpy.parameter import Parameter, parameter_value_to_python
    from rclpy.parameter_client import AsyncParameterClient
    from scenario_runner.autopilot_law import NODE_TABLE as AUTOPILOT_TABLE
    from sim_contract.node_params import NODE_TABLES, STEPPING
    table = {**NODE_TABLES, "autopilot": AUTOPILOT_TABLE + STEPPING}[executable]
    types = {"bool": ParameterType.PARAMETER_BOOL, "integer": ParameterType.PARAMETER_INTEGER,
             "double": ParameterType.PARAMETER_DOUBLE, "string": ParameterType.PARAMETER_STRING,
             "string array": ParameterType.PARAMETER_STRING_ARRAY,
             "double array": ParameterType.PARAMETER_DOUBLE_ARRAY}
    proc = start_node(package, executable, *_ros_args(name, given))
    asker = Node("parameter_asker", context=rclpy_context)
    client = AsyncParameterClient(asker, name)
    assert client.wait_for_services(timeout_sec=60.0), f"no parameter services of {name}:\n{proc.log()}"

    listed = set(_call(asker, lambda: client.list_parameters(), "list").result.names) - ROS_BUILT_INS
    assert listed == set(table.names), (sorted(listed - set(table.names)), sorted(set(table.names) - listed))

    described = _call(asker, lambda: client.describe_parameters(list(table.names)), "describe").descriptors
    values = _call(asker, lambda: client.get_parameters(list(table.names)), "get").values
    for p, d, v in zip(table, described, values):
        assert d.name == p.name and d.type == types[p.ros_type], p.name
        assert v.type == (ParameterType.PARAMETER_NOT_SET if p.default is None else types[p.ros_type]), p.name
        if p.ros_type == "double" and p.lo is not None:
            (r,) = d.floating_point_range
            assert (r.from_value, r.to_value) == (p.lo, p.hi), p.name
            assert d.description == (f"{p.description} [{p.unit}]" if p.unit else p.description)
        elif p.ros_type == "integer" and p.lo is not None:
            (r,) = d.integer_range
            assert (r.from_value, r.to_value) == (p.lo, p.hi), p.name
        else:
            assert d.dynamic_typing == p.dynamic, p.name
            assert not d.floating_point_range and not d.integer_range, p.name
        assert d.read_only == p.read_only, p.name
        assert parameter_value_to_python(v) == given.get(p.name, p.default), p.name

    # while running: a live parameter changes, a fixed one is refused naming the live ones
    if executable not in STEPPED:
        asker.destroy_node()
        return
    fixed = next(p for p in table if not p.live)
    changes = [Parameter(fixed.name, value=fixed.default)]
    if table.live:
        live = table[table.live[0]]
        changes.append(Parameter(live.name, value=(live.lo + live.hi) / 2))
    results = _call(asker, lambda: client.set_parameters(changes), "set").results
    assert not results[0].successful and "fixed at start-up" in results[0].reason
    assert all(n in results[0].reason for n in table.live), results[0].reason
    assert all(r.successful for r in results[1:]), results[1:]
    asker.destroy_node()
