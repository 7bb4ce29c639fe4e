"""The node processes of a run: each in its own process group with its log file and its
pipe to the recorder, or (--layout one_process) the same nodes constructed in the runner's
process."""
from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import time
from typing import Dict, List, Optional

from rclpy.node import Node

from scenario_runner.run_nodes import NodeSpec, RunError, executable_path
from sim_plumbing import record_feed
from sim_plumbing import ros_common as rc
from sim_plumbing import step_channel


def _grow_pipe(fd: int, size: int = 1 << 20) -> None:
    """A node blocks when its feed pipe is full (64 KiB by default): give it room for many steps."""
    try:
        import fcntl
        fcntl.fcntl(fd, getattr(fcntl, "F_SETPIPE_SZ", 1031), size)
    except OSError:
        pass  # above /proc/sys/fs/pipe-max-size: the default size still works, the runner drains every step


def write_group(path: str, specs: List[NodeSpec]) -> None:
    """The node group file a node_group process reads (scenario_runner.node_group.read_group)."""
    import dataclasses
    with open(path, "w") as f:
        json.dump([dataclasses.asdict(s) for s in specs], f)


class NodeProcesses:
    """The node processes of a run, each in its own process group, output to a log file: a node
    alone runs its own executable (as `ros2 run` starts it); a group of several, one node_group
    process composing them (--layout groups). Keyed by the node's name, or the group's names
    joined with " + "."""

    def __init__(self, specs: List[NodeSpec], log_dir: str, recorder=None, channels: bool = False,
                 groups: Optional[List[List[NodeSpec]]] = None):
        self.groups = groups if groups is not None else [[s] for s in specs]
        self.specs = [s for group in self.groups for s in group]
        self.log_dir = log_dir
        self.recorder = recorder  # gets a pipe feed from every node process
        # step participants: each gets a private channel to the runner (sim_plumbing/step_channel.py)
        self.with_channels = channels
        self.channels: Dict[str, step_channel.RunnerEnd] = {}
        self.procs: Dict[str, subprocess.Popen] = {}
        self.logs: Dict[str, str] = {}

    def start(self) -> None:
        os.makedirs(self.log_dir, exist_ok=True)
        # the nodes end when this process does, however it ends (sim_plumbing.ros_common.die_with_parent)
        env = dict(os.environ, PYTHONUNBUFFERED="1", **{rc.PARENT_PID_ENV: str(os.getpid())})
        for index, group in enumerate(self.groups):
            label = " + ".join(s.name for s in group)
            stem = group[0].name.strip("/").replace("/", "_") if len(group) == 1 else f"node_group_{index}"
            log = os.path.join(self.log_dir, stem + ".log")
            self.logs[label] = log
            feed_fds = ()
            for key in (record_feed.ENV_FD, step_channel.ENV_FD, step_channel.ENV_FDS):
                env.pop(key, None)
            if self.recorder is not None:
                read_fd, write_fd = os.pipe()
                _grow_pipe(write_fd)
                self.recorder.add_pipe_feed(read_fd)
                env[record_feed.ENV_FD] = str(write_fd)
                feed_fds = (write_fd,)
            node_fds = {}
            for spec in group:
                if self.with_channels and (spec.package, spec.executable) in CHANNEL_EXECUTABLES:
                    self.channels[spec.name], node_fds[spec.name] = step_channel.socket_pair()
            feed_fds += tuple(node_fds.values())
            if len(group) == 1:
                spec = group[0]
                if node_fds:
                    env[step_channel.ENV_FD] = str(node_fds[spec.name])
                command = [executable_path(spec.package, spec.executable), "--ros-args", *spec.ros_args()]
            else:
                env[step_channel.ENV_FDS] = json.dumps(node_fds)
                group_file = os.path.join(self.log_dir, stem + ".json")
                write_group(group_file, group)
                command = [executable_path("scenario_runner", "node_group"), group_file]
            with open(log, "wb") as out:
                try:
                    self.procs[label] = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT, env=env,
                                                         start_new_session=True, pass_fds=feed_fds)
                finally:
                    for fd in feed_fds:
                        os.close(fd)  # the node holds its ends: the pipe and the channel end when it exits

    def cpu_seconds(self) -> float:
        """CPU time (user + system, all threads) of the node processes so far; nan without /proc."""
        total = 0.0
        for p in self.procs.values():
            try:
                with open(f"/proc/{p.pid}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:
                return float("nan")
            total += (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
        return total

    def dead(self) -> Optional[str]:
        for name, p in self.procs.items():
            if p.poll() is not None:
                return name
        return None

    def tail(self, name: str, lines: int = 15) -> str:
        try:
            with open(self.logs[name], "rb") as f:
                return "\n".join(f.read().decode(errors="replace").splitlines()[-lines:])
        except OSError:
            return ""

    def stop(self, timeout: float = 5.0) -> None:
        for p in self.procs.values():
            if p.poll() is None:
                try:
                    os.killpg(p.pid, signal.SIGINT)
                except ProcessLookupError:
                    pass
        deadline = time.monotonic() + timeout
        for p in self.procs.values():
            try:
                p.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
        for channel in self.channels.values():
            channel.close()


LAYOUTS = ("processes", "one_process", "groups")
DEFAULT_LAYOUT = "groups"


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


# A node's share of a step's work, in vessel steps, for placing nodes in groups: measured per step
# (benchmarks/bench_waves.py, bench_scale.py: a vessel 0.13-0.2 ms, a rope 0.4 ms at 10 elements
# and 0.9 ms at 200, a contact or interaction pair and an autopilot less than a vessel; the
# runner's own round, SimStep and /clock out, answers in, the recording written, about two).
_WEIGHTS = {"vessel_node": 1.0, "contact_node": 0.5, "interaction_node": 0.5, "autopilot": 0.5}
RUNNER_WEIGHT = 2.0


def _weight(spec: NodeSpec) -> float:
    if spec.executable == "rope_node":
        return 2.5 + 0.03 * float(spec.params.get("n_elements", 10))
    return _WEIGHTS.get(spec.executable, 1.0)


def _vessels_of(spec: NodeSpec) -> List[str]:
    """The vessels a node couples (its tow: placed together, their messages stay in the process)."""
    p = spec.params
    if spec.executable == "vessel_node":
        return [spec.namespace.strip("/")]
    names = [str(p[k]).split("/")[0] for k in ("end_a", "end_b") if p.get(k)]
    names += [str(p[k]) for k in ("fender_vessel", "hull_vessel", "vessel_a", "vessel_b", "vessel") if p.get(k)]
    return names


# One weight unit's CPU per step with every node in one process, recorded (bench_harbour: 1.34 ms
# a step for the default demo's 6.8 units, 10 ms for 8 tows' 40.4), and the share of a core's
# exchange period a group may fill: 8 tows in one process (10.3-11.0 ms a step, 55 % of 20 ms)
# held 50 Hz paced with 0 overruns in 3 runs of 1500 steps once the collector's pauses were gone
# (ros_common.settle_heap), where two processes took 17 ms a step (docs/benchmarks.md).
UNIT_CPU_S = 0.25e-3
CORE_SHARE = 0.6


def default_group_count(specs: List[NodeSpec], period_s: float, n_cores: int) -> int:
    """How many processes carry a run by default (--layout groups without --groups): one, the
    runner's own, while the run's work fills at most CORE_SHARE of a core's exchange period (a
    second process doubles the CPU of a step, its messages crossing processes: measured 3.2
    against 1.5 ms for the default demo), else one more per CORE_SHARE, up to the cores (8 tows
    at 50 Hz: one; 10: two)."""
    load = (sum(map(_weight, specs)) + RUNNER_WEIGHT) * UNIT_CPU_S / period_s
    return max(1, min(n_cores, math.ceil(load / CORE_SHARE)))


def node_groups(specs: List[NodeSpec], k: int, runner_weight: float = RUNNER_WEIGHT) -> List[List[NodeSpec]]:
    """The run's nodes in k groups (the first is the runner's own process): whole tows (vessels
    with the ropes, contacts, interactions and autopilots between them) placed largest first on
    the least loaded group, a tow too big for one group's share placed node by node."""
    parent: Dict[str, str] = {}

    def root(x: str) -> str:
        while parent.setdefault(x, x) != x:
            x = parent[x]
        return x
    for spec in specs:
        vessels = _vessels_of(spec) or [spec.name]
        for v in vessels[1:]:
            parent[root(v)] = root(vessels[0])
    tows: Dict[str, List[NodeSpec]] = {}
    for spec in specs:
        tows.setdefault(root((_vessels_of(spec) or [spec.name])[0]), []).append(spec)
    k = max(1, k)
    loads = [runner_weight] + [0.0] * (k - 1)
    groups: List[List[NodeSpec]] = [[] for _ in range(k)]
    share = (sum(map(_weight, specs)) + runner_weight) / k

    def place(items: List[NodeSpec]) -> None:
        g = loads.index(min(loads))
        groups[g] += items
        loads[g] += sum(map(_weight, items))
    for tow in sorted(tows.values(), key=lambda t: -sum(map(_weight, t))):
        if sum(map(_weight, tow)) <= share or k == 1:
            place(tow)
        else:
            for spec in sorted(tow, key=lambda s: -_weight(s)):
                place([spec])
    order = {s.name: i for i, s in enumerate(specs)}   # each group in the scenario's order
    return [sorted(g, key=lambda s: order[s.name]) for g in groups]
# The executables built on sim_plumbing.stepping, which read the runner's private channel. Any other
# step participant (an autopilot of somebody else's package declared in the scenario) speaks the
# protocol on the wire only, and gets no channel: the runner takes its StepDone from the wire, with
# the trust of an external node (docs/step-protocol.md).
CHANNEL_EXECUTABLES = {("tug_dynamics", "vessel_node"), ("rope_model", "rope_node"),
                       ("scenario_runner", "autopilot"), ("hull_contact", "contact_node"),
                       ("hull_contact", "interaction_node")}


def in_process_nodes(specs: List[NodeSpec]) -> List[Node]:
    """The same nodes as the executables start, constructed in this process."""
    from hull_contact.contact_node import ContactNode
    from hull_contact.interaction_node import InteractionNode
    from rope_model.rope_node import RopeNode
    from scenario_runner.autopilot import AutopilotNode
    from tug_dynamics.vessel_node import VesselNode
    classes = {("tug_dynamics", "vessel_node"): VesselNode, ("rope_model", "rope_node"): RopeNode,
               ("scenario_runner", "autopilot"): AutopilotNode, ("hull_contact", "contact_node"): ContactNode,
               ("hull_contact", "interaction_node"): InteractionNode}
    unknown = [s.name for s in specs if (s.package, s.executable) not in classes]
    if unknown:
        raise RunError(f"node(s) {unknown} can only run as their own process (--layout processes)")
    return [classes[(s.package, s.executable)](s.node_name, namespace=s.namespace,
                                               parameter_overrides=s.parameter_overrides()) for s in specs]
