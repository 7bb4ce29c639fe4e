"""The node processes of a run: each in its own process group with its log file and its
pipe to the recorder, or (--layout one_process) the same nodes constructed in the runner's
process."""
from __future__ import annotations

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


class NodeProcesses:
    """The node processes of a run, each in its own process group, output to a log file."""

    def __init__(self, specs: List[NodeSpec], log_dir: str, recorder=None, channels: bool = False):
        self.specs = specs
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
        for spec in self.specs:
            log = os.path.join(self.log_dir, spec.name.strip("/").replace("/", "_") + ".log")
            self.logs[spec.name] = log
            feed_fds = ()
            env.pop(record_feed.ENV_FD, None)
            env.pop(step_channel.ENV_FD, None)
            if self.recorder is not None:
                read_fd, write_fd = os.pipe()
                _grow_pipe(write_fd)
                self.recorder.add_pipe_feed(read_fd)
                env[record_feed.ENV_FD] = str(write_fd)
                feed_fds = (write_fd,)
            if self.with_channels and (spec.package, spec.executable) in CHANNEL_EXECUTABLES:
                self.channels[spec.name], node_fd = step_channel.socket_pair()
                env[step_channel.ENV_FD] = str(node_fd)
                feed_fds += (node_fd,)
            with open(log, "wb") as out:
                try:
                    self.procs[spec.name] = subprocess.Popen(
                        [executable_path(spec.package, spec.executable), "--ros-args", *spec.ros_args()],
                        stdout=out, stderr=subprocess.STDOUT, env=env, start_new_session=True, pass_fds=feed_fds)
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


LAYOUTS = ("processes", "one_process")
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
