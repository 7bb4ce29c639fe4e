"""Pieces every simulator node shares: frames, QoS, step <-> time, quaternions, parameter
descriptors, data files, the executor and spin loop, and main() (run_node).

Time: step k of a run with exchange period T (integer nanoseconds) is stamped k*T exactly, so
a stamp names its step without rounding doubt.
"""
from __future__ import annotations

import gc
import os
import time
import zlib
from typing import Callable, Optional

from builtin_interfaces.msg import Time
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from sim_contract import topics
from sim_plumbing.dds_profile import use_discovery_profile

WORLD_FRAME = "map"  # REP-105 world-fixed frame, ENU (REP-103), still-water surface at z = 0
EVENTS_TOPIC = topics.EVENTS

# State topics read off the step protocol (a free-running autopilot): reliable, volatile, so it
# matches any publisher of the contract; lockstep participants read LATCHED_STATE_QOS.
STATE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=50,
                       reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
# Commands as offered by a sender: reliable, a few deep; late joiners do not get stale orders.
COMMAND_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                         reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
# Commands as a node takes them: keep-all, so the node's own reader history never drops an order
# (measured: a keep-last-10 reader passed on 422 of a burst of 10,000). Orders a sender's own
# keep-last history overwrites before delivery never reach the node, unseen: DDS's sample-lost
# event would report them but deadlocks rmw_fastrtps on Jazzy, so no node takes it (stepping.py).
COMMAND_SUB_QOS = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.VOLATILE)
# Frames (tf2_msgs/TFMessage) with tf2_ros's QoS: /tf as its TransformBroadcaster (reliable,
# volatile, keep last 100), /tf_static as its StaticTransformBroadcaster (reliable,
# transient-local, keep last 1: a late subscriber gets each publisher's static frames).
TF_TOPIC = topics.TF
TF_STATIC_TOPIC = topics.TF_STATIC
TF_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE,
                    durability=DurabilityPolicy.VOLATILE)
TF_STATIC_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE,
                           durability=DurabilityPolicy.TRANSIENT_LOCAL)
EVENTS_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                        reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
CLOCK_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


def period_ns(rate_hz: float) -> int:
    ns = round(1e9 / rate_hz)
    if ns <= 0:
        raise ValueError(f"exchange rate {rate_hz} Hz gives no usable period")
    return ns


def step_time(step: int, period: int) -> Time:
    total = step * period
    return Time(sec=total // 1_000_000_000, nanosec=total % 1_000_000_000)


def time_to_ns(t: Time) -> int:
    return t.sec * 1_000_000_000 + t.nanosec


def float_param(description: str, lo: float, hi: float, unit: str = "") -> ParameterDescriptor:
    text = f"{description} [{unit}]" if unit else description
    return ParameterDescriptor(description=text, floating_point_range=[
        FloatingPointRange(from_value=float(lo), to_value=float(hi), step=0.0)])


def int_param(description: str, lo: int, hi: int) -> ParameterDescriptor:
    return ParameterDescriptor(description=description, integer_range=[
        IntegerRange(from_value=int(lo), to_value=int(hi), step=1)])


def text_param(description: str) -> ParameterDescriptor:
    return ParameterDescriptor(description=description)


def descriptor(param) -> ParameterDescriptor:
    """The ROS descriptor of a row of a parameter table (sim_contract.node_params.Param): a number
    with a range gets a range (the unit in its description), anything else its description."""
    if param.dynamic:
        return ParameterDescriptor(description=param.description, dynamic_typing=True)
    if param.read_only:
        return ParameterDescriptor(description=param.description, read_only=True)
    if param.lo is not None and param.ros_type == "double":
        return float_param(param.description, param.lo, param.hi, param.unit)
    if param.lo is not None and param.ros_type == "integer":
        return int_param(param.description, param.lo, param.hi)
    return text_param(f"{param.description} [{param.unit}]" if param.unit else param.description)


def declare_table(node, table) -> None:
    """Declare every parameter of a node's table (sim_contract.node_params) with its default and
    descriptor, in the table's order."""
    without_default = {"double": Parameter.Type.DOUBLE, "integer": Parameter.Type.INTEGER,
                       "string": Parameter.Type.STRING, "bool": Parameter.Type.BOOL}
    for param in table:
        value = without_default[param.kind] if param.default is None else param.default
        node.declare_parameter(param.name, value, descriptor(param))


def refuse_fixed_parameters(node, table) -> None:
    """`ros2 param set` of a parameter the table does not call live is refused: the node reads it
    at start-up only, so a change would be accepted and never applied (stepped nodes do this in
    SteppedNode, which also hands live changes to the model)."""
    live = table.live
    node.add_on_set_parameters_callback(
        lambda params: fixed_parameters_refused(params, live) or SetParametersResult(successful=True))


def fixed_parameters_refused(params, live) -> Optional[SetParametersResult]:
    """The refusal of a parameter change naming the parameters in it that are not live (fixed at
    start-up), or None when every one of them may change while the node runs."""
    fixed = sorted(p.name for p in params if p.name not in live)
    if not fixed:
        return None
    return SetParametersResult(successful=False, reason=(
        f"{', '.join(fixed)}: fixed at start-up (restart the node to change it); parameters that "
        f"change while running: {', '.join(live) or 'none'}"))


# ---------------------------------------------------------------------------------------
# Stepping: lockstep participant or free-running node.
# ---------------------------------------------------------------------------------------
SIM_STEP_TOPIC = topics.SIM_STEP
STEP_DONE_TOPIC = topics.STEP_DONE
# Outputs of a step must reach late joiners (e.g. a node that matched after step 0 was sent).
LATCHED_STATE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=50,
                               reliability=ReliabilityPolicy.RELIABLE,
                               durability=DurabilityPolicy.TRANSIENT_LOCAL)
# Volatile on purpose: a trigger or answer of an earlier run in the same domain must never reach
# a later one. Nothing is lost at start-up: nodes repeat StepDone(0) until triggered, and the
# runner sends SimStep(0) only once every participant's subscription has matched.
PROTOCOL_QOS = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.VOLATILE)
# The profile of each QoS kind of the topic contract (sim_contract.topics), as offered.
QOS_BY_KIND = {"latched_state": LATCHED_STATE_QOS, "command": COMMAND_QOS, "protocol": PROTOCOL_QOS,
               "clock": CLOCK_QOS, "events": EVENTS_QOS, "tf": TF_QOS, "tf_static": TF_STATIC_QOS}


def message_class(ros_type: str):
    """The Python class of a ROS type named as the contract names it ("nav_msgs/msg/Odometry")."""
    import importlib
    package, kind, name = ros_type.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


EXECUTORS = ("events", "single")


def make_executor(kind: str | None = None):
    """The executor every simulator process uses: rclpy's EventsExecutor (default; several
    times faster per callback than the SingleThreadedExecutor, see the README benchmark) or the
    classic one (TUGSIM_EXECUTOR=single)."""
    kind = kind or os.environ.get("TUGSIM_EXECUTOR", "events")
    if kind not in EXECUTORS:
        raise ValueError(f"TUGSIM_EXECUTOR={kind!r}: expected one of {EXECUTORS}")
    if kind == "events":
        from rclpy.experimental import EventsExecutor
        return EventsExecutor()
    from rclpy.executors import SingleThreadedExecutor
    return SingleThreadedExecutor()


def ran_into_shutdown(exc: Exception) -> bool:
    """Is exc what a spin round raises when the context is shut down under it (SIGTERM, or
    Ctrl-C through rclpy's signal handler)? Measured here by stopping nodes at random moments:
    RCLError from a callback publishing on the shut-down context ("publisher's context is
    invalid"), the executor's ExternalShutdownException, and a plain RuntimeError from pybind11
    when the signal's KeyboardInterrupt lands while it converts a call argument."""
    from rclpy.executors import ExternalShutdownException
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    if isinstance(exc, (ExternalShutdownException, _rclpy.RCLError)):
        return True
    return type(exc) is RuntimeError and "Unable to convert call argument" in str(exc)


def spin_forever(executor, poll: Optional[Callable[[], None]] = None,
                 say: Optional[Callable[[str], None]] = None) -> None:
    """Spin until shutdown. spin_once in a loop: the Jazzy EventsExecutor's spin() does not
    fire timers (measured here), spin_once does. poll() runs after every round, whatever the
    executor's timers do. A round that ran into the shutdown (ran_into_shutdown) ends the loop
    and say() tells what it raised (not a ROS logger: /rosout is gone by then); any other
    exception propagates."""
    import rclpy
    while rclpy.ok(context=executor.context):
        try:
            executor.spin_once(timeout_sec=0.1)
            if poll is not None:
                poll()
        except Exception as exc:
            if rclpy.ok(context=executor.context) or not ran_into_shutdown(exc):
                raise
            if say is not None:
                what = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
                say(f"stopped: the last round ran into the shutdown ({what})")
            return


def take_missed(subscription, callback, limit: int = 10_000) -> int:
    """Take what a subscription's reader holds and hand it to callback, bypassing the executor;
    returns how many. A second line of defence around rclpy's EventsExecutor (experimental in
    Jazzy): a node that makes no progress takes what its readers hold rather than wait for an
    executor callback. (The flood stalls once blamed on the executor were a deadlock in
    rmw_fastrtps' sample-lost event, which the nodes no longer subscribe to; see stepping.py.)"""
    taken = 0
    with subscription.handle:
        while taken < limit:
            got = subscription.handle.take_message(subscription.msg_type, subscription.raw)
            if got is None:
                break
            callback(got[0])
            taken += 1
    return taken


PARENT_PID_ENV = "TUGSIM_PARENT_PID"


def marker_step(node_name: str, step: int, every: int) -> bool:
    """Whether a node draws its markers at this step: every `every`-th step, at a phase of its
    own (its full name's CRC-32 modulo `every`), so the nodes of a run spread their drawing over
    the steps instead of all drawing on the same one (eight tows in one process: 24 nodes)."""
    return (step - zlib.crc32(node_name.encode()) % every) % every == 0


def settle_heap() -> None:
    """Collect once and freeze what is left (gc.freeze): called when a node is ready and by the
    runner before its clock starts. The start-up's objects (numba, LLVM, DDS, the models) then
    sit outside the collector, whose later passes walk only what the run itself makes: in the
    berthing run, paced, the older-generation passes took 0.6-1.7 ms and a full one 14-66 ms,
    enough to make a step late (issue 34, docs/benchmarks.md)."""
    gc.collect()
    gc.freeze()


def die_with_parent() -> None:
    """A node started by the scenario runner (which sets TUGSIM_PARENT_PID) ends when the runner
    does, however the runner ended (SIGKILL included): Linux's parent-death signal delivers
    SIGTERM at once, and a watch thread covers what that misses (a parent that died before the
    signal was armed, other kernels)."""
    import signal
    import threading
    text = os.environ.get(PARENT_PID_ENV)
    if not text:
        return
    parent = int(text)
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass  # no libc to load, or no prctl in it (not Linux): the watch thread below covers it
    if os.getppid() != parent:
        os.kill(os.getpid(), signal.SIGTERM)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os.kill(os.getpid(), signal.SIGTERM)
    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def init_rclpy(args=None, **kwargs) -> None:
    """rclpy.init with the simulator's discovery profile (dds_profile.use_discovery_profile)."""
    import rclpy
    use_discovery_profile()
    rclpy.init(args=args, **kwargs)


class ModelDiverged(RuntimeError):
    """The model's state went non-finite or blew up: numerics, not physics (named with the step).
    A node's main() (run_node) ends with exit 3 naming it."""


def run_node(make_node, program: str, args=None, bad_input=(ValueError, KeyError, FileNotFoundError),
             failures=()) -> int:
    """main() of a simulator node: construct, spin until Ctrl-C / SIGTERM, clean up.

    Exit status: 0 stopped, 2 bad parameters or files (bad_input, message on stderr), 3 the
    model failed (failures, e.g. a diverged rope, or a state gone non-finite; message on stderr).
    Once the node has spun, the process ends in here (os._exit): a node's main() is its process."""
    return run_nodes(lambda: [make_node()], program, args, bad_input, failures)


def run_nodes(make_nodes, program: str, args=None, bad_input=(ValueError, KeyError, FileNotFoundError),
              failures=()) -> int:
    """run_node for several nodes composed in one process on one executor (make_nodes() returns
    them; scenario_runner.node_group): the same exit statuses, the first failure ends them all."""
    import sys

    import rclpy
    from rclpy.exceptions import ParameterException

    failures = (*failures, ModelDiverged) if isinstance(failures, tuple) else (failures, ModelDiverged)
    init_rclpy(args)
    die_with_parent()
    try:
        nodes = make_nodes()
    except (*bad_input, ParameterException) as exc:
        sys.stderr.write(f"{program}: {exc}\n")
        rclpy.try_shutdown()
        return 2
    except KeyboardInterrupt:
        rclpy.try_shutdown()
        return 0
    executor = make_executor()
    for node in nodes:
        executor.add_node(node)
    polls = [node.poll for node in nodes if hasattr(node, "poll")]

    def poll_all() -> None:
        for poll in polls:
            poll()
    status = 0
    try:
        spin_forever(executor, poll_all if polls else None, lambda text: sys.stderr.write(f"{program}: {text}\n"))
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass
    except failures as exc:
        sys.stderr.write(f"{program}: {exc}\n")
        status = 3
    finally:
        executor.shutdown()
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown()
    exit_process(status)


def exit_process(status: int) -> None:
    """End the process now, its output flushed, once ROS is shut down and every file closed:
    Python's own finalisation of the loaded numba/LLVM and DDS objects takes 0.3-0.4 s per
    process here, and a run waits for each of its nodes."""
    import sys
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
