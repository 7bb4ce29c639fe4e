"""Stamps for outside tools (send_command, the console, ...): simulation time whenever /clock is
published, wall time otherwise.

A message an outside tool sends into a run is stamped with the time it was given. In a run the
scenario runner owns /clock (step k: k * T), and the recording, the analysis and every node
read stamps as simulation time; a wall-clock stamp (about 1.8e9 s) lies outside the run, and
`analyze` could not place the order. rclpy's `use_sim_time` alone does not do: without a
/clock publisher its time stays 0. SimClock follows /clock when there is one and says which
time it gives.
"""
from __future__ import annotations

import time
from typing import Optional

from builtin_interfaces.msg import Time
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

CLOCK_TOPIC = "/clock"


class SimClock:
    """The newest /clock of the graph a node is on, or the node's wall clock without one."""

    def __init__(self, node):
        self.node = node
        self.latest: Optional[Time] = None
        self.received_at = 0.0  # time.monotonic() of the newest /clock
        # best effort takes the runner's reliable /clock too, and never holds it up
        self._sub = node.create_subscription(Clock, CLOCK_TOPIC, self._on_clock,
                                             QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))

    def _on_clock(self, msg: Clock) -> None:
        self.latest = msg.clock
        self.received_at = time.monotonic()

    def published(self) -> bool:
        """Someone (a scenario runner, a replay) publishes /clock."""
        return self.node.count_publishers(CLOCK_TOPIC) > 0

    def wait(self, executor_or_spin, timeout: float = 2.0, discovery: float = 1.0) -> bool:
        """Spin (spin_once(timeout_sec=...) of an executor, or a callable taking timeout_sec)
        until the first /clock arrives: at most `discovery` s while no /clock publisher is known
        (Fast DDS may take a moment to show the runner), at most `timeout` s in all. True if
        the stamps are simulation time."""
        spin = getattr(executor_or_spin, "spin_once", executor_or_spin)
        start = time.monotonic()
        while self.latest is None:
            now = time.monotonic()
            if now > start + timeout or (now > start + discovery and not self.published()):
                break
            spin(timeout_sec=0.01)
        return self.latest is not None

    @property
    def source(self) -> str:
        return "simulation time (/clock)" if self.latest is not None else "wall time (no /clock)"

    def now(self) -> Time:
        """The stamp to put on a message given now."""
        if self.latest is not None:
            return self.latest
        return self.node.get_clock().now().to_msg()

    def now_ns(self) -> int:
        t = self.now()
        return t.sec * 1_000_000_000 + t.nanosec
