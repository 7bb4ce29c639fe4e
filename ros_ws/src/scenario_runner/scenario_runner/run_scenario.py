"""Run a scenario headless.

    ros2 run scenario_runner run_scenario default_demo.yaml --output output/demo.mcap

The scenario is validated before any node starts (errors name the file and the key); then
the nodes are started (--layout: by default in as few processes as the run's work needs, this
one first; or every node its own process, as `ros2 run` starts them), the run is stepped in lockstep (or paced real
time), progress is shown, everything is shut down, and a summary is printed. With --external the
runner drives nodes somebody else started (other PCs; --print-nodes gives their commands): it
waits for them to announce themselves and records their outputs by subscription. Exit status:
0 done, 2 invalid scenario or output (also: another run still writing the same --output, whose
recording is left untouched), 3 a node died / stopped answering / failed, 4 the ROS domain is
in use by another run (refused before step 0, no recording left), 5 the run cannot be trusted (a
stranger publishes its state, a node got two different messages for one step, or the step count
does not match what a node published: named; the recording is kept for inspection), 130 Ctrl-C,
143 SIGTERM (both stop the nodes and finalise the recording).
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import os
import signal
import sys
from typing import Callable, Dict, List, Optional, Tuple

import rclpy
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.serialization import deserialize_message
from tug_msgs.msg import RopeState, ScenarioEvent

from scenario_runner import conductor as cd
from scenario_runner import run_nodes
from scenario_runner.node_processes import CORE_SHARE, DEFAULT_LAYOUT, LAYOUTS, cores
from scenario_runner.run_summary import summary, write_runner_notes
from scenario_runner.autopilot_law import check_scenario_params as check_autopilot_params
from recording.recorder import McapRecorder, OutputClaim, RecordingInUse, readable_extent
from scenario_format.particulars import recording_metadata, scenario_path
from scenario_format.scenario import Scenario, ScenarioError, load_scenario
from sim_contract import topics as T
from sim_contract.node_params import LIVE_VIEW
from sim_plumbing import cdr
from sim_plumbing import ros_common as rc



class Monitor(Node):
    """Collects what the summary needs: towline end tensions, partings and final vessel states.

    It takes the serialized bytes of the few topics it needs, from the recorder when one runs
    (no second subscription, no second delivery per step), else from its own raw
    subscriptions; only the small end wrench is decoded every step. Without a recorder the
    final odometry is fetched once the run is over (finish(): the odometry topics are
    transient-local, a late subscription gets the last messages), not taken every step."""

    def __init__(self, sc, recorder: Optional[McapRecorder] = None):
        super().__init__("scenario_monitor")
        self.tension: Dict[str, List[float]] = {}
        self.broken: Dict[str, bool] = {r.name: False for r in sc.ropes}
        self._odom_raw: Dict[str, bytes] = {}
        self._odom_topics: Dict[str, str] = {}  # vessel -> topic, fetched by finish()
        self.vessels = [v.name for v in sc.vessels]
        wanted = []  # (topic, type, qos, callback on the serialized message)
        for r in sc.ropes:
            end = next((e for e in ("a", "b") if "/" in getattr(r, f"end_{e}")), None)
            self.tension[r.name] = []
            if end is not None:
                wanted.append((T.end_wrench_topic(r.name, end), WrenchStamped,
                               lambda data, r=r.name: self._wrench(r, data)))
            else:  # both ends fixed or free: the rope state's end a force
                wanted.append((T.rope_topic(r.name, T.STATE), RopeState, lambda data, r=r.name: self._rope(r, data)))
        for topic, msg_type, callback in wanted:
            if recorder is not None and recorder.tap(topic, callback):
                continue
            self.create_subscription(msg_type, topic, callback, rc.LATCHED_STATE_QOS, raw=True)
        for v in sc.vessels:
            topic = T.vessel_topic(v.name, T.ODOM)
            if recorder is None or not recorder.tap(topic, lambda data, v=v.name: self._odom_raw.__setitem__(v, data)):
                self._odom_topics[v.name] = topic
        self.create_subscription(ScenarioEvent, rc.EVENTS_TOPIC, self._event, rc.EVENTS_QOS)

    @property
    def odom(self) -> Dict[str, Odometry]:
        """The last odometry of each vessel (decoded on demand)."""
        return {v: deserialize_message(data, Odometry) for v, data in self._odom_raw.items()}

    def finish(self, final_stamp_ns: int) -> Callable[[], bool]:
        """After the last step: subscribe the odometry not tapped from the recorder; returns
        whether the final step's odometry of every vessel is in."""
        def keep_last(vessel: str, data: bytes) -> None:
            if cdr.CdrReader(data).stamp_ns() == final_stamp_ns:
                self._odom_raw[vessel] = data
        for vessel, topic in self._odom_topics.items():
            self.create_subscription(Odometry, topic, lambda data, v=vessel: keep_last(v, data),
                                     rc.LATCHED_STATE_QOS, raw=True)
        return lambda: all(v in self._odom_raw for v in self.vessels)

    def _wrench(self, name: str, data: bytes) -> None:
        f = cdr.decode_wrench_stamped(data).force
        self.tension[name].append(math.sqrt(f[0] ** 2 + f[1] ** 2 + f[2] ** 2))

    def _rope(self, name: str, data: bytes) -> None:
        f = deserialize_message(data, RopeState).end_a_force
        self.tension[name].append(math.sqrt(f.x ** 2 + f.y ** 2 + f.z ** 2))

    def _event(self, msg: ScenarioEvent) -> None:
        if msg.kind == "rope_parted" and msg.target in self.broken:
            self.broken[msg.target] = True


def check_writable(path: str, what: str) -> Optional[str]:
    """Why a file cannot be written at path, or None. Checked before anything starts (and without
    creating anything), so a bad path is a message, not a traceback after the run."""
    if os.path.isdir(path):
        return f"{what} {path} is a folder, expected a file name"
    if os.path.exists(path) and not os.path.isfile(path):
        return f"{what} {path} is not a regular file"
    folder = os.path.dirname(os.path.abspath(path))
    existing = folder
    while not os.path.exists(existing):
        existing = os.path.dirname(existing)
    if not os.path.isdir(existing):
        return f"{what} {path}: cannot create the folder {folder}: {existing} is not a folder"
    if not os.access(existing, os.W_OK | os.X_OK) or existing.startswith("/proc"):
        return f"{what} {path}: cannot create or write the folder {folder} ({existing} is not writable)"
    return None


@dataclasses.dataclass
class RunPlan:
    """What a validated command line runs: the scenario and where its files go."""
    path: str  # the scenario file
    sc: Scenario
    steps: int
    output: str  # the recording
    log_dir: str
    record: bool
    external: List[str] = dataclasses.field(default_factory=list)  # node names the runner does not start


def _group_count(text: str) -> int:
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number of processes, at least 1, got {text!r}")
    return int(text)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="run_scenario", description=__doc__.split("\n\n")[0])
    parser.add_argument("scenario", help="scenario file, or a name in share/scenario_runner/scenarios")
    parser.add_argument("--output", help="MCAP file to write (default: output/<scenario name>.mcap)")
    parser.add_argument("--duration", type=float, help="simulate only this many seconds (shortened run)")
    parser.add_argument("--log-dir", help="where node logs go (default: next to the recording)")
    parser.add_argument("--layout", choices=LAYOUTS, default=DEFAULT_LAYOUT,
                        help="processes: every node its own process (as `ros2 run` starts them); "
                             "one_process: all nodes in this process on one executor; "
                             "groups: the nodes in --groups processes (this one the first), whole tows together")
    parser.add_argument("--groups", type=_group_count, metavar="K",
                        help=f"processes of --layout groups, this one included (default: one while the run's work "
                             f"fills {CORE_SHARE:g} of a core's exchange period, else more, up to the cores: {cores()} here)")
    parser.add_argument("--no-record", action="store_true", help="do not record (overrides the scenario)")
    pace = parser.add_mutually_exclusive_group()
    pace.add_argument("--realtime", dest="mode", action="store_const", const="realtime",
                      help="pace the run on the wall clock, one simulated second a second (overrides the "
                           "scenario's mode): for people at the console, the page or send_command")
    pace.add_argument("--lockstep", dest="mode", action="store_const", const="lockstep",
                      help="run as fast as the nodes compute (overrides the scenario's mode)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.add_argument("--live", action="store_true",
                        help="serve the run to Foxglove / Lichtblick on a WebSocket (live_view package)")
    parser.add_argument("--live-port", type=int, default=LIVE_VIEW["port"].default,
                        help=f"WebSocket port of --live (default {LIVE_VIEW['port'].default})")
    parser.add_argument("--live-host", default="127.0.0.1", help="address --live listens on (default 127.0.0.1)")
    parser.add_argument("--live-rate", type=float, default=20.0,
                        help="rate at which --live sends new messages to its clients, Hz (default 20)")
    parser.add_argument("--external", action="append", default=[], metavar="NODES",
                        help="nodes this runner does not start (comma-separated; a node name such as /tug/vessel, "
                             "its namespace such as tug, or all): somebody starts them, e.g. on other PCs "
                             "(--print-nodes); the runner waits for them to announce themselves, steps, watches "
                             "and records them like its own")
    parser.add_argument("--print-nodes", action="store_true",
                        help="print the `ros2 run` command of every node of the scenario and exit")
    parser.add_argument("--run-id", help="this run's id (default: random); nodes started with -p run_id:=<it> "
                                         "take part in this run only")
    parser.add_argument("--stall-timeout", type=float, default=30.0,
                        help="s without an answer after which a node counts as stopped (default 30)")
    parser.add_argument("--ready-timeout", type=float, default=240.0,
                        help="s to wait for every node to announce itself at start-up (default 240)")
    return parser


def node_commands(plan: "RunPlan", run_id: str = "") -> List[str]:
    """The `ros2 run` command line of every node of the scenario (for --external: what to start
    on the other PCs). Without a run id the nodes join the first run that starts."""
    import shlex
    lines = []
    for spec in run_nodes.node_specs(plan.sc, plan.path, run_id, portable=True):
        args = spec.ros_args()
        if not run_id:
            i = args.index("run_id:=" + run_nodes.yaml_value(""))
            del args[i - 1:i + 1]
        lines.append(shlex.join(["ros2", "run", spec.package, spec.executable, "--ros-args", *args]))
    return lines


def live_topics(sc: Scenario) -> List[Tuple[str, str, bool]]:
    """(topic, type, transient-local) the live view serves: the contract, and the frames and
    vessel scenes."""
    from rclpy.qos import DurabilityPolicy
    from sim_plumbing.msg_definitions import type_name
    # a vessel on a prescribed motion takes no orders: the web clients are refused them at the edge
    # (the vessel would refuse them too, after the live view had answered "accepted")
    no_orders = {T.vessel_topic(v.name, name) for v in sc.vessels if v.motion is not None
                 for name in (T.COMMAND, T.THRUSTER_COMMAND)}
    topics = [(t, type_name(cls), qos.durability == DurabilityPolicy.TRANSIENT_LOCAL)
              for t, cls, qos in run_nodes.contract_topics(sc) if t not in no_orders]
    extra = [(rc.TF_TOPIC, "tf2_msgs/msg/TFMessage", False), (rc.TF_STATIC_TOPIC, "tf2_msgs/msg/TFMessage", True)]
    extra += [(T.vessel_topic(v.name, T.MARKERS), "visualization_msgs/msg/MarkerArray", True) for v in sc.vessels]
    have = {t[0] for t in topics}
    return topics + [t for t in extra if t[0] not in have]


def _add_tap(recorder: McapRecorder, topic: str, callback: Callable[[bytes], None]) -> bool:
    """Hand the recorder's bytes of topic to callback too (after any tap already there)."""
    before = recorder.taps.get(topic)
    if before is None:
        return recorder.tap(topic, callback)

    def both(data: bytes) -> None:
        before(data)
        callback(data)
    return recorder.tap(topic, both)


def start_live_view(sc: Scenario, path: str, args, recorder: Optional[McapRecorder]):
    """The live view node in this process: it takes every recorded topic from the recorder as
    written (no second DDS delivery) and subscribes the rest; it gets the run's environment as
    the vessel nodes do (the instructor station draws the same sea)."""
    from live_view.live_view_node import LiveViewNode
    from rclpy.parameter import Parameter
    from scenario_format.scenario import environment_parameter
    topics = live_topics(sc)
    offered = [t[0] for t in topics if recorder is not None and t[0] in recorder.channels]
    node = LiveViewNode(topics=topics, offered_topics=offered, parameter_overrides=[
        Parameter("port", value=int(args.live_port)), Parameter("host", value=str(args.live_host)),
        Parameter("rate", value=float(args.live_rate)), Parameter("discover", value=False),
        Parameter("environment", value=environment_parameter(sc, path))])
    for t in offered:
        _add_tap(recorder, t, lambda data, t=t: node.offer(t, data))
    return node


def main(argv: Optional[List[str]] = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = build_parser().parse_args(rclpy.utilities.remove_ros_args(argv))
    plan, exit_code = plan_run(args)
    if plan is None:
        return exit_code
    if args.print_nodes:
        print("\n".join(node_commands(plan, args.run_id or "")))
        return 0
    # The runner handles SIGINT and SIGTERM itself (conductor.StopSignals: noted, acted on at the
    # next check; rclpy's handlers would shut the context down under the running loop, an RCLError
    # traceback or exit 3). A signal while starting abandons the start and keeps nothing; the run
    # loop's StopSignals takes over a signal noted just before it.
    starting = cd.StopSignals().__enter__()
    try:  # the output is this run's before anything starts: a run still writing it is not touched
        claim = OutputClaim(plan.output) if plan.record else None
    except OSError as exc:
        starting.__exit__()
        why = "refused to start" if isinstance(exc, RecordingInUse) else f"cannot write the recording {plan.output}"
        sys.stderr.write(f"run_scenario: {why}: {exc}\n")
        return 2
    rc.init_rclpy(argv, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    rc.exit_process(run_and_report(plan, args, claim, starting))


def _abandoned(starting: cd.StopSignals, recorder: Optional[McapRecorder], claim: Optional[OutputClaim],
               nodes=()) -> Optional[int]:
    """If a signal came while starting: everything made so far undone (the recording discarded:
    start-up messages only), said on stderr; the exit status 128 + signal. Else None."""
    if starting.signum is None:
        return None
    if recorder:
        recorder.close(discard=True)
    elif claim:
        claim.release()
    for node in nodes:
        if node is not None:
            node.destroy_node()
    rclpy.try_shutdown()
    sys.stderr.write(f"run_scenario: interrupted by {signal.Signals(starting.signum).name} while starting; "
                     "nothing was run, no recording written\n")
    return 128 + int(starting.signum)


def run_and_report(plan: RunPlan, args, claim: Optional[OutputClaim], starting: cd.StopSignals) -> int:
    """The run of a checked plan (rclpy initialised, the output claimed, signals noted by
    `starting`), its summary printed; the exit status."""
    try:
        recorder = McapRecorder(plan.output, run_nodes.contract_topics(plan.sc),
                                fed_topics=run_nodes.fed_topics(plan.sc, plan.external),
                                by_stamp=run_nodes.external_outputs(plan.sc, plan.external)[0],
                                metadata=recording_metadata(plan.path, plan.sc), claim=claim) if plan.record else None
    except OSError as exc:
        sys.stderr.write(f"run_scenario: cannot write the recording {plan.output}: {exc}\n")
        rclpy.try_shutdown()
        return 2
    mon = Monitor(plan.sc, recorder)
    live = None
    if args.live and starting.signum is None:
        try:
            live = start_live_view(plan.sc, plan.path, args, recorder)
        except Exception as exc:  # noqa: BLE001 - e.g. the port is taken: said before anything starts
            sys.stderr.write(f"run_scenario: --live: cannot start the live view on {args.live_host}:"
                             f"{args.live_port}: {exc}\n")
            if recorder:
                recorder.close(discard=True)  # start-up messages only: not a recording
            mon.destroy_node()
            rclpy.try_shutdown()
            return 2
    abandoned = _abandoned(starting, recorder, claim, (mon, live))
    if abandoned is not None:
        return abandoned
    if live is not None:
        print(f"live view: ws://{args.live_host}:{live.port} (Foxglove / Lichtblick: open connection, "
              f"Foxglove WebSocket)", flush=True)
    stats, exit_code = execute(plan, args, recorder, mon, live)
    if stats is None:
        return exit_code
    print(summary(plan.sc, stats, mon))
    write_runner_notes(plan.log_dir, stats)
    if recorder:
        print(f"  recording: {os.path.abspath(plan.output)} ({sum(recorder.counts.values())} messages on "
              f"{len(recorder.counts)} topics)" + (f"; not recorded, undecodable: {recorder.refused}"
                                                   if recorder.refused else ""))
    print(f"  node logs: {plan.log_dir}")
    return 0


def plan_run(args) -> Tuple[Optional[RunPlan], int]:
    """(the run the arguments ask for, 0), or (None, exit status 2) with the reason on stderr:
    checked before anything starts (scenario, duration, output paths)."""
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        sys.stderr.write(f"run_scenario: --duration {args.duration!r}: expected a finite number of seconds > 0\n")
        return None, 2
    for option in ("stall_timeout", "ready_timeout"):
        value = getattr(args, option, None)
        if value is not None and not (math.isfinite(value) and value > 0):
            sys.stderr.write(f"run_scenario: --{option.replace('_', '-')} {value!r}: expected a finite number of "
                             "seconds > 0\n")
            return None, 2
    path = scenario_path(args.scenario)
    try:
        sc = load_scenario(path)
        for i, a in enumerate(sc.autopilots):
            check_autopilot_params(path, i, a)
    except ScenarioError as exc:
        sys.stderr.write(f"run_scenario: invalid scenario:\n{exc}\n")
        return None, 2
    for warning in sc.warnings:
        sys.stderr.write(f"run_scenario: warning: {path}: {warning}\n")
    if getattr(args, "mode", None):  # --realtime / --lockstep
        sc = sc.model_copy(update={"mode": args.mode})
    steps = sc.steps if args.duration is None else min(sc.steps, int(round(args.duration * sc.exchange_rate)))
    output = args.output or sc.recording.path or os.path.join("output", f"{sc.name}.mcap")
    stem = os.path.splitext(os.path.basename(output))[0] or sc.name
    # the logs follow the recording's name: two runs to two files never share a log folder
    log_dir = args.log_dir or os.path.join(os.path.dirname(os.path.abspath(output)), f"{stem}_logs")
    record = sc.recording.enabled and not args.no_record
    problem = check_writable(output, "recording (--output)") if record else None
    problem = problem or check_writable(os.path.join(log_dir, "x.log"), "log folder (--log-dir)")
    if problem:
        sys.stderr.write(f"run_scenario: {problem}\n")
        return None, 2
    try:
        wanted = ",".join(getattr(args, "external", None) or []).split(",")
        external = run_nodes.resolve_external(run_nodes.node_specs(sc, path), wanted)
    except ValueError as exc:
        sys.stderr.write(f"run_scenario: {exc}\n")
        return None, 2
    if record and os.path.exists(output) and not getattr(args, "print_nodes", False):
        sys.stderr.write(f"run_scenario: replacing the existing recording {os.path.abspath(output)} "
                         "(give --output to keep it)\n")
    return RunPlan(path, sc, steps, output, log_dir, record, external), 0


def execute(plan: RunPlan, args, recorder: Optional[McapRecorder], mon: Monitor,
            live: Optional[Node] = None) -> Tuple[Optional[cd.RunStats], int]:
    """Run the scenario with a progress bar; (stats, 0), or (None, exit status) with the reason
    on stderr. The recording is finalised and ROS shut down whatever happens."""
    output = plan.output
    progress = None
    if not args.quiet:
        from tqdm import tqdm
        progress = tqdm(total=plan.steps, unit="step", desc=plan.sc.name, file=sys.stderr, mininterval=0.5)
    finalise_failed = refused = False
    try:
        stats = cd.run(plan.sc, plan.path, plan.log_dir, steps=plan.steps, extra_nodes=[mon] + ([live] if live else []),
                       recorder=recorder,
                       layout=args.layout, groups=getattr(args, "groups", None),
                       on_step=(lambda k: progress.update(1)) if progress else None,
                       on_finished=mon.finish, external=plan.external, run_id=getattr(args, "run_id", None),
                       stall_timeout=getattr(args, "stall_timeout", 30.0),
                       ready_timeout=getattr(args, "ready_timeout", 240.0))
    except OSError as exc:  # the recording could not be written (disk full, file system gone)
        if progress:
            progress.close()
        sys.stderr.write(f"run_scenario: run stopped: writing {os.path.abspath(output)} failed: {exc}\n")
        if recorder is not None and recorder.failure is not None:
            sys.stderr.write(f"run_scenario: the recording ends readably where the write failed: "
                             f"{readable_extent(output)}\n")
        return None, 3
    except cd.DomainInUse as exc:
        if progress:
            progress.close()
        sys.stderr.write(f"run_scenario: refused to start: {exc}\n")
        refused = True
        return None, 4
    except cd.Untrusted as exc:
        if progress:
            progress.close()
        sys.stderr.write(f"run_scenario: run stopped, untrusted: {exc}\n")
        return None, 5
    except cd.RunError as exc:
        if progress:
            progress.close()
        sys.stderr.write(f"run_scenario: run stopped: {exc}\n")
        return None, 3
    except (cd.Interrupted, KeyboardInterrupt, rclpy.executors.ExternalShutdownException) as exc:
        signum = exc.args[0] if isinstance(exc, cd.Interrupted) else signal.SIGINT
        sys.stderr.write(f"run_scenario: interrupted by {signal.Signals(signum).name}; nodes stopped"
                         + (f", partial recording finalised: {os.path.abspath(output)}" if recorder else "") + "\n")
        return None, 128 + int(signum)
    finally:
        if progress:
            progress.close()
        if recorder:
            try:
                recorder.close(discard=refused)  # finalised (summary, indexes) also after an error or Ctrl-C
            except OSError as exc:
                sys.stderr.write(f"run_scenario: the recording {os.path.abspath(output)} could not be "
                                 f"finalised: {exc}; it ends readably where the write failed: "
                                 f"{readable_extent(output)}\n")
                finalise_failed = True
            if refused:  # no step was run: a file of start-up messages would pass for a recording
                sys.stderr.write(f"run_scenario: no recording written ({os.path.abspath(output)} removed)\n")
        mon.destroy_node()
        if live is not None:
            live.destroy_node()
        rclpy.try_shutdown()
    if finalise_failed:
        return None, 3
    return stats, 0


if __name__ == "__main__":
    sys.exit(main())
