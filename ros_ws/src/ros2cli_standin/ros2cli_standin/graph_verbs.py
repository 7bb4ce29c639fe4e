"""`ros2 topic`, `ros2 node` and `ros2 param` for the ros2cli stand-in (scripts/ros2).

ros2cli is not on PyPI, so scripts/ros2 hands these verbs to this module, which does what ros2cli
(Jazzy) does with rclpy's graph API, an ordinary subscription and the standard parameter services
(rcl_interfaces: /<node>/list_parameters, get_parameters, set_parameters, describe_parameters),
printing in ros2cli's formats:

  ros2 topic list [-t] [-c] [-v] [--include-hidden-topics]
  ros2 topic info <topic> [-v]
  ros2 topic echo <topic> [<type>] [--once] [--timeout N] [--field a.b] [--no-arr] [--no-str]
                  [--flow-style] [-l N | -f] [--qos-profile P] [--qos-reliability R]
                  [--qos-durability D] [--qos-depth N] [--qos-history H]
  ros2 topic hz <topic> [--window N]
  ros2 node list [-a] [-c]
  ros2 param list [<node>] [--param-type] [--filter REGEX] [--param-prefixes P ...]
  ros2 param get <node> <name> [--hide-type]
  ros2 param set <node> <name> <value>

Discovery: there is no ros2 daemon here, so every call discovers the graph afresh, and Fast DDS
may see a running participant only at that participant's next announcement, up to 3 s later. So
a list or a count (topic list, topic info, node list, param list without a node) waits
--spin-time S (default 3.5 s; ros2cli's 0.5 s gives a quick but often incomplete answer) and
until the graph has not changed for 0.3 s. A named topic or node is used as soon as it is seen
(echo, hz, param get/set: typically well under a second, at most ~3 s), and reported unknown
after DISCOVERY_TIMEOUT (4 s).

Where the stand-in knowingly differs from ros2cli (Jazzy):
- `topic echo` of a topic nobody publishes yet: like ros2cli it prints
  "WARNING: topic [/x] does not appear to be published yet" and fails ("Could not determine the
  type ..."), after waiting up to 4 s for discovery instead of ros2cli's 0.5 s; `topic hz`, like
  ros2cli, prints the warning and waits for the topic until Ctrl-C.
- `param set` that the node refuses exits 1 (ros2cli prints the same line but exits 0).
- Ctrl-C (SIGINT) or SIGTERM end echo and hz quietly with exit 0 (ros2cli exits 2 on Ctrl-C).
- The stand-in's own node (`_ros2cli_<pid>`, hidden like ros2cli's) is left out of
  `node list -a`; relative topic names are expanded (`tug/odom` is `/tug/odom`) for info too.
- Errors begin with ros2cli's text and name what is missing ("Node not found: '/x' (nodes seen:
  ...)", "Parameter not set: node /n has no parameter 'p'", "Unknown topic '/t' (...)").
- Not offered: echo --csv/--raw/--filter/-i, hz --filter, and the other verbs of ros2cli.

The node is created with rclpy's signal handlers off; SIGINT reaches Python as
KeyboardInterrupt between two short spins.
"""
from __future__ import annotations

import argparse
import array
import importlib
import math
import os
import re
import signal
import sys
import time
from collections import OrderedDict
from typing import Callable, List, Optional

NODE_NAME_PREFIX = "_ros2cli_"  # rclpy's HIDDEN_NODE_PREFIX + "ros2cli_", as ros2cli names its node
# How long a list or a count waits for discovery (--spin-time; ros2cli's is 0.5 s, with its daemon
# holding the graph). Without a daemon every call discovers afresh, and Fast DDS often sees a
# running participant only at that participant's next periodic announcement (every 3 s): a new
# process saw a running vessel node after 0.03-2.8 s here, with ROS_AUTOMATIC_DISCOVERY_RANGE
# LOCALHOST (as the tests run) and SUBNET alike; with 0.5 s most lists came out incomplete.
DEFAULT_SPIN_TIME = 3.5
DISCOVERY_TIMEOUT = 4.0  # s a named topic or node is waited for
GRAPH_SETTLE = 0.3  # s without a graph change before a snapshot is taken as complete
SERVICE_TIMEOUT = 5.0  # s for the parameter services to appear (ros2cli's), and again for the answer
DEFAULT_TRUNCATE_LENGTH = 128  # ros2cli echo's
DEFAULT_WINDOW_SIZE = 10000  # ros2cli hz's
INTERRUPTED_EXIT = 0  # exit status of echo/hz ended by Ctrl-C or SIGTERM


class Failure(Exception):
    """A command failed: the message goes to stderr, the exit status is 1 (as ros2cli's)."""


class _Stop(BaseException):
    """SIGTERM, raised where Python handles the signal (like KeyboardInterrupt for SIGINT)."""


# -- messages: types and YAML (rosidl_runtime_py's when it is installed) -------------------------
def get_message(identifier: str):
    """The message class of 'pkg/msg/Type' (or 'pkg/Type')."""
    try:
        from rosidl_runtime_py.utilities import get_message as _get
        return _get(identifier)
    except ImportError:
        pass
    parts = identifier.split("/")
    if len(parts) == 2:
        parts = [parts[0], "msg", parts[1]]
    if len(parts) != 3 or not all(parts) or parts[1] != "msg":
        raise ValueError(f"Invalid message type '{identifier}': expected <package>/msg/<Type>")
    module = importlib.import_module(f"{parts[0]}.msg")
    cls = getattr(module, parts[2])
    if not hasattr(cls, "SLOT_TYPES") or not hasattr(cls, "get_fields_and_field_types"):
        raise ValueError(f"'{identifier}' is not a message type")
    return cls


def message_to_yaml(msg, *, truncate_length: Optional[int] = None, no_arr: bool = False,
                    no_str: bool = False, flow_style: bool = False) -> str:
    """rosidl_runtime_py.message_to_yaml (ros2 topic echo's format); its own when installed."""
    try:
        from rosidl_runtime_py import message_to_yaml as _to_yaml
        return _to_yaml(msg, truncate_length=truncate_length, no_arr=no_arr, no_str=no_str,
                        flow_style=flow_style)
    except ImportError:
        pass
    import yaml

    class _Dumper(yaml.Dumper):
        pass

    def _represent_ordereddict(dumper, data):
        return yaml.nodes.MappingNode("tag:yaml.org,2002:map",
                                      [(dumper.represent_data(k), dumper.represent_data(v))
                                       for k, v in data.items()])

    _Dumper.add_representer(OrderedDict, _represent_ordereddict)
    return yaml.dump(message_to_ordereddict(msg, truncate_length=truncate_length, no_arr=no_arr,
                                            no_str=no_str),
                     Dumper=_Dumper, allow_unicode=True, width=sys.maxsize, default_flow_style=flow_style)


def _type_name(value_type) -> str:
    from rosidl_parser import definition as d
    if isinstance(value_type, d.BasicType):
        return value_type.typename
    if isinstance(value_type, d.AbstractString):
        return "string"
    if isinstance(value_type, d.AbstractWString):
        return "wstring"
    if isinstance(value_type, d.NamedType):
        return value_type.name
    if isinstance(value_type, d.NamespacedType):
        return "/".join(value_type.namespaced_name())
    return "unknown"


def _abbreviate_array(value, field_type) -> str:
    from rosidl_parser import definition as d
    name = _type_name(field_type.value_type)
    if isinstance(field_type, d.Array):
        return f"<array type: {name}[{field_type.size}]>"
    if isinstance(field_type, d.BoundedSequence):
        return f"<sequence type: {name}[{field_type.maximum_size}], length: {len(value)}>"
    if isinstance(field_type, d.UnboundedSequence):
        return f"<sequence type: {name}, length: {len(value)}>"
    return "unknown"


def message_to_ordereddict(msg, *, truncate_length=None, no_arr=False, no_str=False) -> OrderedDict:
    out = OrderedDict()
    for name, field_type in zip(msg.get_fields_and_field_types().keys(), msg.SLOT_TYPES):
        out[name] = _convert(getattr(msg, name, None), field_type, truncate_length, no_arr, no_str)
    return out


def _convert(value, field_type, truncate_length, no_arr, no_str):
    import numpy
    if isinstance(value, bytes):
        if truncate_length is not None and len(value) > truncate_length:
            return "".join(chr(c) for c in value[:truncate_length]) + "..."
        return "".join(chr(c) for c in value)
    if isinstance(value, str):
        if no_str:
            return f"<string length: <{len(value)}>>"
        if truncate_length is not None and len(value) > truncate_length:
            return value[:truncate_length] + "..."
        return value
    if isinstance(value, (list, tuple, array.array, numpy.ndarray)):
        kind = tuple if isinstance(value, tuple) else list
        if no_arr and field_type is not None:
            return _abbreviate_array(value, field_type)
        tail = []
        if truncate_length is not None and len(value) > truncate_length:
            value, tail = value[:truncate_length], ["..."]
        return kind([_convert(v, None, truncate_length, no_arr, no_str) for v in value] + tail)
    if isinstance(value, dict):
        return {_convert(k, None, None, False, False): _convert(v, None, truncate_length, no_arr, no_str)
                for k, v in value.items()}
    if isinstance(value, numpy.number):
        return value.item()
    if isinstance(value, (bool, float, int)) or value is None:
        return value
    return message_to_ordereddict(value, truncate_length=truncate_length, no_arr=no_arr, no_str=no_str)


# -- the command-line node -----------------------------------------------------------------------
class CliNode:
    """rclpy context + hidden node `_ros2cli_<pid>` + executor, and graph waiting."""

    def __init__(self, spin_time: float):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions
        self.rclpy = rclpy
        self.spin_time = DEFAULT_SPIN_TIME if spin_time is None else spin_time
        self.context = rclpy.Context()
        rclpy.init(args=["ros2"], context=self.context, signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node(f"{NODE_NAME_PREFIX}{os.getpid()}", context=self.context,
                                      start_parameter_services=False)
        self.full_name = self.node.get_fully_qualified_name()
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._started = time.monotonic()

    def close(self) -> None:
        try:
            self.executor.shutdown(timeout_sec=0.5)
            self.node.destroy_node()
        finally:
            self.rclpy.try_shutdown(context=self.context)

    # graph
    def node_names(self, include_hidden: bool = False) -> List[str]:
        """Fully qualified names of the other nodes (hidden ones, `_...`, only if asked)."""
        names = []
        for name, ns in self.node.get_node_names_and_namespaces():
            full = ns + ("" if ns.endswith("/") else "/") + name
            if full == self.full_name or not name or (name.startswith("_") and not include_hidden):
                continue
            names.append(full)
        return names

    def topics(self, include_hidden: bool = True):
        from rclpy.topic_or_service_is_hidden import topic_or_service_is_hidden
        return sorted((n, list(t)) for n, t in self.node.get_topic_names_and_types()
                      if include_hidden or not topic_or_service_is_hidden(n))

    def topic_types(self, topic: str) -> Optional[List[str]]:
        for name, types in self.node.get_topic_names_and_types():
            if name == topic:
                return list(types)
        return None

    def _snapshot(self, extra: Optional[Callable] = None):
        return (sorted(self.node.get_node_names_and_namespaces()), self.topics(),
                extra() if extra is not None else None)

    def wait_graph(self, found: Optional[Callable[[], bool]] = None, complete: bool = False,
                   timeout: float = DISCOVERY_TIMEOUT, extra: Optional[Callable] = None) -> bool:
        """Wait for discovery until found() (if given) and the graph (and extra(), if given) has
        not changed for GRAPH_SETTLE s; complete: also at least spin_time since start (a list or a
        count needs every participant, not just the one named). At most max(spin_time, timeout)
        (+ 3 s without found) in all. Returns found() (True without it)."""
        minimum = self.spin_time if complete else 0.0
        deadline = self._started + (max(minimum, timeout) if found is not None else minimum + 3.0)
        last, last_change = self._snapshot(extra), time.monotonic()
        while True:
            now = time.monotonic()
            ok = found is None or found()
            if ok and now - self._started >= minimum and now - last_change >= GRAPH_SETTLE:
                return True
            if now >= deadline:
                return ok
            time.sleep(0.05)
            snap = self._snapshot(extra)
            if snap != last:
                last, last_change = snap, time.monotonic()

    def expand_topic(self, topic: str) -> str:
        from rclpy.expand_topic_name import expand_topic_name
        from rclpy.validate_full_topic_name import validate_full_topic_name
        try:
            name = expand_topic_name(topic, self.node.get_name(), self.node.get_namespace())
            validate_full_topic_name(name)
        except Exception as exc:  # rclpy raises ValueError or InvalidTopicNameException
            raise Failure(f"Invalid topic name '{topic}': {exc}")
        return name

    def wait_node(self, node_name: str, include_hidden: bool = False, timeout: float = DISCOVERY_TIMEOUT) -> None:
        if not self.wait_graph(lambda: node_name in self.node_names(include_hidden), timeout=timeout):
            known = sorted(self.node_names(include_hidden))
            raise Failure(f"Node not found: '{node_name}' (nodes seen: {', '.join(known) or 'none'}; "
                          f"`ros2 node list` lists them)")

    def spin_until(self, future, timeout: float):
        deadline = time.monotonic() + timeout
        while not future.done() and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.1)
        return future.done()


def absolute_node_name(name: str) -> str:
    return name if name.startswith("/") else "/" + name


# -- topic ---------------------------------------------------------------------------------------
def topic_list(cli: CliNode, args) -> int:
    cli.wait_graph(complete=True)
    topics = cli.topics(include_hidden=args.include_hidden_topics)
    if args.count_topics:
        print(len(topics))
        return 0
    if not topics:
        return 0
    if args.verbose:
        for publishers in (True, False):
            lines = ["Published topics:" if publishers else "Subscribed topics:"]
            for name, types in topics:
                count = cli.node.count_publishers(name) if publishers else cli.node.count_subscribers(name)
                if count:
                    what = "publisher" if publishers else "subscriber"
                    lines.append(f" * {name} [{', '.join(types)}] {count} {what}{'s' if count > 1 else ''}")
            print("\n".join(lines) + "\n")
        return 0
    for name, types in topics:
        print(f"{name} [{', '.join(types)}]" if args.show_types else name)
    return 0


def topic_info(cli: CliNode, args) -> int:
    topic = cli.expand_topic(args.topic_name)
    found = cli.wait_graph(lambda: cli.topic_types(topic) is not None, complete=True,
                           extra=lambda: (cli.node.count_publishers(topic), cli.node.count_subscribers(topic)))
    if not found:
        raise Failure(f"Unknown topic '{topic}' (no publisher or subscription seen; `ros2 topic list` "
                      "lists the topics)")
    types = cli.topic_types(topic)
    end = "\n\n" if args.verbose else "\n"
    print(f"Type: {types[0] if len(types) == 1 else types}", end=end)
    print(f"Publisher count: {cli.node.count_publishers(topic)}", end=end)
    if args.verbose:
        for info in cli.node.get_publishers_info_by_topic(topic):
            print(info, end=end)
    print(f"Subscription count: {cli.node.count_subscribers(topic)}", end=end)
    if args.verbose:
        for info in cli.node.get_subscriptions_info_by_topic(topic):
            print(info, end=end)
    return 0


def _message_class(cli: CliNode, topic: str, given_type: Optional[str], block: bool):
    """The topic's message class: the given type, else the graph's (waiting for discovery)."""
    if given_type is not None:
        try:
            return get_message(given_type)
        except (AttributeError, ModuleNotFoundError, ValueError) as exc:
            raise Failure(f"The passed message type is invalid: '{given_type}' ({exc})")
    if not cli.wait_graph(lambda: cli.topic_types(topic) is not None):
        print(f"WARNING: topic [{topic}] does not appear to be published yet", flush=True)
        if not block:
            raise Failure(f"Could not determine the type for the passed topic '{topic}': no publisher or "
                          f"subscription seen in {max(cli.spin_time, DISCOVERY_TIMEOUT):g} s (`ros2 topic list` "
                          "lists the topics; or pass the type: ros2 topic echo <topic> <pkg/msg/Type>)")
        while cli.topic_types(topic) is None:
            time.sleep(0.1)
    types = cli.topic_types(topic)
    if len(types) > 1:
        raise Failure(f"Cannot echo topic '{topic}', as it contains more than one type: [{', '.join(types)}]")
    try:
        return get_message(types[0])
    except (AttributeError, ModuleNotFoundError, ValueError) as exc:
        raise Failure(f"The message type '{types[0]}' is invalid ({exc}); is the workspace that defines it "
                      "sourced?")


def _echo_qos(cli: CliNode, topic: str, args):
    """ros2cli's choice: the preset (default sensor_data) with the overrides given, else made
    compatible with every publisher (reliable / transient local if all of them are)."""
    from rclpy.qos import (QoSDurabilityPolicy, QoSHistoryPolicy, QoSPresetProfiles, QoSProfile,
                           QoSReliabilityPolicy)
    preset = QoSPresetProfiles.get_from_short_key(args.qos_profile)
    profile = QoSProfile(**{name: getattr(preset, name) for name in (
        "history", "depth", "reliability", "durability", "lifespan", "deadline", "liveliness",
        "liveliness_lease_duration", "avoid_ros_namespace_conventions")})
    overrides = (args.qos_reliability, args.qos_durability, args.qos_depth, args.qos_history)
    if any(v is not None for v in overrides):
        if args.qos_history:
            profile.history = QoSHistoryPolicy.get_from_short_key(args.qos_history)
        if args.qos_durability:
            profile.durability = QoSDurabilityPolicy.get_from_short_key(args.qos_durability)
        if args.qos_reliability:
            profile.reliability = QoSReliabilityPolicy.get_from_short_key(args.qos_reliability)
        if args.qos_depth is not None and args.qos_depth >= 0:
            profile.depth = args.qos_depth
        elif profile.durability == QoSDurabilityPolicy.TRANSIENT_LOCAL and profile.depth == 0:
            profile.depth = 1
        return profile
    publishers = cli.node.get_publishers_info_by_topic(topic)
    if not publishers:
        return profile
    def common(policy: str, strong, weak):
        """strong if every publisher offers it, else weak (ros2cli's warning when some do)."""
        offering = sum(getattr(p.qos_profile, policy) == strong for p in publishers)
        if offering == len(publishers):
            return strong
        if offering:
            name = type(strong).__name__
            print(f"Some, but not all, publishers are offering {name}.{strong.name}. Falling back to "
                  f"{name}.{weak.name} as it will connect to all publishers")
        return weak

    profile.reliability = common("reliability", QoSReliabilityPolicy.RELIABLE, QoSReliabilityPolicy.BEST_EFFORT)
    profile.durability = common("durability", QoSDurabilityPolicy.TRANSIENT_LOCAL, QoSDurabilityPolicy.VOLATILE)
    return profile


def topic_echo(cli: CliNode, args) -> int:
    topic = cli.expand_topic(args.topic_name)
    fields = None
    if args.field is not None:
        fields = [f for f in args.field.split(".") if f]
        if not fields:
            raise Failure(f"Invalid field value '{args.field}'")
    msg_class = _message_class(cli, topic, args.message_type, block=False)
    qos = _echo_qos(cli, topic, args)
    truncate = None if args.full_length else args.truncate_length
    state = {"done": False, "error": None}

    def on_message(msg):
        if state["done"]:
            return
        sub = msg
        for f in fields or ():
            try:
                sub = getattr(sub, f)
            except AttributeError as exc:
                state["error"] = f"Invalid field '{'.'.join(fields)}': {exc}"
                state["done"] = True
                return
        if args.once:
            state["done"] = True
        if not hasattr(sub, "__slots__"):
            print(sub, end="\n---\n")
            return
        print(message_to_yaml(sub, truncate_length=truncate, no_arr=args.no_arr, no_str=args.no_str,
                              flow_style=args.flow_style), end="---\n")

    cli.node.create_subscription(msg_class, topic, on_message, qos)
    deadline = None if args.timeout is None else time.monotonic() + args.timeout
    while not state["done"] and (deadline is None or time.monotonic() < deadline):
        cli.executor.spin_once(timeout_sec=0.1)
    if state["error"]:
        raise Failure(state["error"])
    return 0


class TopicHz:
    """ros2cli's ROSTopicHz for one topic: intervals between arrivals (node clock) over a window,
    a line each time a second has passed since the last one."""

    def __init__(self, clock, window_size: int):
        self.clock, self.window_size = clock, window_size
        self.msg_t0, self.msg_tn, self.last_printed_tn = -1, 0, 0
        self.times: List[int] = []

    def on_message(self, _msg) -> None:
        now = self.clock.now().nanoseconds
        if now == 0:
            if self.times:
                print("time has reset, resetting counters")
                self.times = []
            return
        if self.msg_t0 < 0 or self.msg_t0 > now:
            self.msg_t0 = self.msg_tn = now
            self.times = []
        else:
            self.times.append(now - self.msg_tn)
            self.msg_tn = now
        if len(self.times) > self.window_size:
            self.times.pop(0)

    def get_hz(self):
        if not self.times:
            return None
        if self.last_printed_tn == 0:
            self.last_printed_tn = self.msg_tn
            return None
        if self.msg_tn < self.last_printed_tn + 1e9:
            return None
        n = len(self.times)
        mean = sum(self.times) / n
        rate = 1.0 / mean if mean > 0.0 else 0.0
        std_dev = math.sqrt(sum((x - mean) ** 2 for x in self.times) / n)
        self.last_printed_tn = self.msg_tn
        return rate, min(self.times), max(self.times), std_dev, n

    def print_hz(self) -> None:
        stats = self.get_hz()
        if stats is not None:
            rate, lo, hi, std_dev, n = stats
            print("average rate: %.3f\n\tmin: %.3fs max: %.3fs std dev: %.5fs window: %s"
                  % (rate * 1e9, lo * 1e-9, hi * 1e-9, std_dev * 1e-9, n))


def topic_hz(cli: CliNode, args) -> int:
    from rclpy.clock import Clock, ClockType
    from rclpy.qos import qos_profile_sensor_data
    topic = cli.expand_topic(args.topic_name)
    msg_class = _message_class(cli, topic, None, block=True)
    clock = Clock(clock_type=ClockType.SYSTEM_TIME) if args.use_wtime else cli.node.get_clock()
    hz = TopicHz(clock, args.window_size)
    # raw: only the arrival time matters, so the message is not deserialized
    cli.node.create_subscription(msg_class, topic, hz.on_message, qos_profile_sensor_data, raw=True)
    while True:
        cli.executor.spin_once(timeout_sec=0.1)
        hz.print_hz()


# -- node ----------------------------------------------------------------------------------------
def node_list(cli: CliNode, args) -> int:
    cli.wait_graph(complete=True)
    names = sorted(cli.node_names(include_hidden=args.all))
    if args.count_nodes:
        print(len(names))
    elif names:
        if len(set(names)) < len(names):
            print("WARNING: Be aware that there are nodes in the graph that share an exact name, which can have "
                  "unintended side effects.", file=sys.stderr)
        print(*names, sep="\n")
    return 0


# -- param ---------------------------------------------------------------------------------------
def _param_client(cli: CliNode, node_name: str):
    from rclpy.parameter_client import AsyncParameterClient
    client = AsyncParameterClient(cli.node, node_name)
    if not client.wait_for_services(timeout_sec=SERVICE_TIMEOUT):
        raise Failure(f"Wait for service timed out waiting for parameter services for node {node_name}")
    return client


def _call(cli: CliNode, node_name: str, future):
    if not cli.spin_until(future, SERVICE_TIMEOUT):
        raise Failure(f"No answer from the parameter services of node {node_name} in {SERVICE_TIMEOUT:g} s")
    if future.result() is None:
        raise Failure(f"Exception while calling service of node '{node_name}': {future.exception()}")
    return future.result()


def _type_string(parameter_type: int) -> str:
    from rcl_interfaces.msg import ParameterType as T
    return {T.PARAMETER_BOOL: "boolean", T.PARAMETER_INTEGER: "integer", T.PARAMETER_DOUBLE: "double",
            T.PARAMETER_STRING: "string", T.PARAMETER_BYTE_ARRAY: "byte array",
            T.PARAMETER_BOOL_ARRAY: "boolean array", T.PARAMETER_INTEGER_ARRAY: "integer array",
            T.PARAMETER_DOUBLE_ARRAY: "double array", T.PARAMETER_STRING_ARRAY: "string array",
            T.PARAMETER_NOT_SET: "not set"}.get(parameter_type, f"unknown type {parameter_type}")


def param_list(cli: CliNode, args) -> int:
    wanted = absolute_node_name(args.node_name) if args.node_name else None
    if wanted:
        cli.wait_node(wanted, args.include_hidden_nodes)
        nodes = [wanted]
    else:
        cli.wait_graph(complete=True)
        nodes = cli.node_names(args.include_hidden_nodes)
    # ros2cli's order: by node name, then namespace
    nodes.sort(key=lambda full: (full.rsplit("/", 1)[1], full.rsplit("/", 1)[0] or "/", full))
    regex = re.compile(args.filter[0]) if args.filter else None
    from rclpy.parameter_client import AsyncParameterClient
    status = 0
    for node_name in nodes:
        client = AsyncParameterClient(cli.node, node_name)
        if not client.wait_for_services(timeout_sec=SERVICE_TIMEOUT):
            message = f"Wait for service timed out waiting for parameter services for node {node_name}"
            if wanted:
                raise Failure(message)
            print(message)
            continue
        try:
            names = sorted(_call(cli, node_name, client.list_parameters(prefixes=args.param_prefixes)).result.names)
        except Failure as exc:
            print(exc, file=sys.stderr)
            status = 1
            continue
        if regex is not None:
            names = [n for n in names if regex.match(n)]
        if not wanted and names:
            print(f"{node_name}:")
        types = {}
        if args.param_type and names:
            answer = _call(cli, node_name, client.describe_parameters(names))
            types = {d.name: _type_string(d.type) for d in answer.descriptors}
        for name in names:
            print(f"  {name} (type: {types.get(name)})" if args.param_type else f"  {name}")
    return status


def param_get(cli: CliNode, args) -> int:
    from rcl_interfaces.msg import ParameterType as T
    node_name = absolute_node_name(args.node_name)
    cli.wait_node(node_name, args.include_hidden_nodes, max(args.timeout, DISCOVERY_TIMEOUT))
    client = _param_client(cli, node_name)
    values = _call(cli, node_name, client.get_parameters([args.parameter_name])).values
    if not values:
        raise Failure(f"Parameter not set: node {node_name} has no parameter '{args.parameter_name}' "
                      f"(`ros2 param list {node_name}` lists them)")
    v = values[0]
    labels = {
        T.PARAMETER_BOOL: ("Boolean value is:", lambda: v.bool_value),
        T.PARAMETER_INTEGER: ("Integer value is:", lambda: v.integer_value),
        T.PARAMETER_DOUBLE: ("Double value is:", lambda: v.double_value),
        T.PARAMETER_STRING: ("String value is:", lambda: v.string_value),
        T.PARAMETER_BYTE_ARRAY: ("Byte values are:", lambda: v.byte_array_value),
        T.PARAMETER_BOOL_ARRAY: ("Boolean values are:", lambda: v.bool_array_value),
        T.PARAMETER_INTEGER_ARRAY: ("Integer values are:", lambda: v.integer_array_value.tolist()),
        T.PARAMETER_DOUBLE_ARRAY: ("Double values are:", lambda: v.double_array_value.tolist()),
        T.PARAMETER_STRING_ARRAY: ("String values are:", lambda: v.string_array_value),
        T.PARAMETER_NOT_SET: ("Parameter not set.", lambda: None),
    }
    if v.type not in labels:
        raise Failure(f"Unknown parameter type '{v.type}'")
    label, value = labels[v.type][0], labels[v.type][1]()
    if args.hide_type:
        print(value)
    elif value is None:
        print(label)
    else:
        print(label, value)
    return 0


def param_set(cli: CliNode, args) -> int:
    from rcl_interfaces.msg import Parameter
    from rclpy.parameter import get_parameter_value
    node_name = absolute_node_name(args.node_name)
    cli.wait_node(node_name, args.include_hidden_nodes, max(args.timeout, DISCOVERY_TIMEOUT))
    client = _param_client(cli, node_name)
    parameter = Parameter(name=args.parameter_name, value=get_parameter_value(string_value=args.value))
    results = _call(cli, node_name, client.set_parameters([parameter])).results
    if len(results) != 1:
        raise Failure(f"Node {node_name} answered {len(results)} results to setting one parameter")
    result = results[0]
    if result.successful:
        print("Set parameter successful" + (f": {result.reason}" if result.reason else ""))
        return 0
    print("Setting parameter failed" + (f": {result.reason}" if result.reason else ""), file=sys.stderr)
    return 1


# -- command line --------------------------------------------------------------------------------
def _int_at_least(least: int, message: str):
    """argparse type: an int >= least, else ros2cli's own message."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = least - 1
        if value < least:
            raise argparse.ArgumentTypeError(message)
        return value
    return parse


_positive_int = _int_at_least(1, "value must be a positive integer")
_unsigned_int = _int_at_least(0, "value must be non-negative integer")


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError("Expects a floating point number")
    if not value > 0.0:
        raise argparse.ArgumentTypeError("Value must be positive")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="ros2", description="ros2cli stand-in: topic, node and param verbs")
    commands = parser.add_subparsers(dest="command", metavar="<command>")
    commands.required = True

    def verb(group, name, help_text, func):
        p = group.add_parser(name, help=help_text, description=help_text)
        p.add_argument("--spin-time", type=float, default=None,
                       help="Seconds a list or count waits for discovery (default: %g; ros2cli's 0.5 is "
                            "quicker but often incomplete)" % DEFAULT_SPIN_TIME)
        p.set_defaults(func=func)
        return p

    topic = commands.add_parser("topic", help="Various topic related sub-commands").add_subparsers(
        dest="verb", metavar="<verb>")
    topic.required = True
    p = verb(topic, "list", "Output a list of available topics", topic_list)
    p.add_argument("-t", "--show-types", action="store_true", help="Additionally show the topic type")
    p.add_argument("-c", "--count-topics", action="store_true", help="Only display the number of topics discovered")
    p.add_argument("--include-hidden-topics", action="store_true", help="Consider hidden topics as well")
    p.add_argument("-v", "--verbose", action="store_true", help="List full details about each topic")

    p = verb(topic, "info", "Print information about a topic", topic_info)
    p.add_argument("topic_name", help="Name of the ROS topic to get info (e.g. '/chatter')")
    p.add_argument("-v", "--verbose", action="store_true",
                   help="Prints the node name, topic type, GID and QoS profile of every publisher and subscriber")

    from rclpy.qos import (QoSDurabilityPolicy, QoSHistoryPolicy, QoSPresetProfiles,
                           QoSReliabilityPolicy)
    p = verb(topic, "echo", "Output messages from a topic", topic_echo)
    p.add_argument("topic_name", help="Name of the ROS topic to listen to (e.g. '/chatter')")
    p.add_argument("message_type", nargs="?", help="Type of the ROS message (e.g. 'std_msgs/msg/String')")
    p.add_argument("--qos-profile", choices=QoSPresetProfiles.short_keys(), default="sensor_data",
                   help="Quality of service preset profile to subscribe with (default: sensor_data)")
    p.add_argument("--qos-depth", metavar="N", type=int, help="Queue size setting to subscribe with")
    p.add_argument("--qos-history", choices=QoSHistoryPolicy.short_keys(), help="History of samples setting")
    p.add_argument("--qos-reliability", choices=QoSReliabilityPolicy.short_keys(),
                   help="Reliability setting (default: compatible with the publishers)")
    p.add_argument("--qos-durability", choices=QoSDurabilityPolicy.short_keys(),
                   help="Durability setting (default: compatible with the publishers)")
    p.add_argument("--field", type=str, default=None,
                   help="Echo a selected field of a message, '.' selects sub-fields (e.g. pose.pose.position)")
    p.add_argument("--full-length", "-f", action="store_true",
                   help="Output all elements of arrays, bytes and strings longer than --truncate-length")
    p.add_argument("--truncate-length", "-l", type=_unsigned_int, default=DEFAULT_TRUNCATE_LENGTH,
                   help="The length to truncate arrays, bytes, and string to (default: %d)" % DEFAULT_TRUNCATE_LENGTH)
    p.add_argument("--no-arr", action="store_true", help="Don't print array fields of messages")
    p.add_argument("--no-str", action="store_true", help="Don't print string fields of messages")
    p.add_argument("--flow-style", action="store_true", help="Print collections in the flow style")
    p.add_argument("--once", action="store_true", help="Print the first message received and then exit.")
    p.add_argument("--timeout", metavar="N", type=_positive_float, default=None,
                   help="Stop after N seconds (exit 0)")

    p = verb(topic, "hz", "Print the average publishing rate to screen", topic_hz)
    p.add_argument("topic_name", help="Name of the ROS topic to listen to (e.g. '/chatter')")
    p.add_argument("--window", "-w", dest="window_size", type=_positive_int, default=DEFAULT_WINDOW_SIZE,
                   metavar="WINDOW",
                   help="window size, in # of messages, for calculating rate (default: %d)" % DEFAULT_WINDOW_SIZE)
    p.add_argument("--wall-time", dest="use_wtime", action="store_true",
                   help="calculates rate using wall time (the same here: the stand-in never uses sim time)")

    node = commands.add_parser("node", help="Various node related sub-commands").add_subparsers(
        dest="verb", metavar="<verb>")
    node.required = True
    p = verb(node, "list", "Output a list of available nodes", node_list)
    p.add_argument("-a", "--all", action="store_true", help="Display all nodes even hidden ones")
    p.add_argument("-c", "--count-nodes", action="store_true", help="Only display the number of nodes discovered")

    param = commands.add_parser("param", help="Various param related sub-commands").add_subparsers(
        dest="verb", metavar="<verb>")
    param.required = True
    p = verb(param, "list", "Output a list of available parameters", param_list)
    p.add_argument("node_name", nargs="?", help="Name of the ROS node")
    p.add_argument("--filter", nargs=1, help="Only parameters matching the regex expression (Python re)")
    p.add_argument("--include-hidden-nodes", action="store_true", help="Consider hidden nodes as well")
    p.add_argument("--param-prefixes", nargs="+", default=[], help="Only list parameters with the provided prefixes")
    p.add_argument("--param-type", action="store_true", help="Print parameter types with parameter names")
    for name, help_text, func in (("get", "Get parameter", param_get), ("set", "Set parameter", param_set)):
        p = verb(param, name, help_text, func)
        p.add_argument("node_name", help="Name of the ROS node")
        p.add_argument("--include-hidden-nodes", action="store_true", help="Consider hidden nodes as well")
        p.add_argument("parameter_name", help="Name of the parameter")
        if name == "get":
            p.add_argument("--hide-type", action="store_true", help="Hide the type information")
        else:
            p.add_argument("value", help="Value of the parameter (YAML: true, 3, 0.5, [1, 2], text)")
        p.add_argument("--timeout", metavar="N", type=int, default=1,
                       help="Wait for N seconds until node becomes available (at least %g here)" % DISCOVERY_TIMEOUT)
    return parser


def _on_sigterm(signum, frame):
    raise _Stop()


def main(argv: List[str]) -> int:
    """Run `ros2 <argv>` for argv[0] in topic, node, param; returns the exit status."""
    try:
        sys.stdout.reconfigure(line_buffering=True)
    except AttributeError:
        pass
    args = build_parser().parse_args(argv)
    cli = None
    # Ctrl-C as KeyboardInterrupt even when started with SIGINT ignored (a parent that ignores it,
    # e.g. a pytest-xdist worker, passes that on through exec), as ros2cli's rclpy handlers do
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        cli = CliNode(args.spin_time)
        return args.func(cli, args)
    except (Failure, RuntimeError) as exc:  # ros2cli too prints a RuntimeError's message, exit 1
        print(exc, file=sys.stderr)
        return 1
    except (KeyboardInterrupt, _Stop):
        return INTERRUPTED_EXIT
    except BrokenPipeError:
        # `ros2 topic echo ... | head`: the reader is gone; stop quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        if cli is not None:
            try:
                cli.close()
            except Exception:
                pass
