"""Step protocol shared by every simulator node (vessel, rope).

A node computes the state of step k+1 from inputs stamped with step k. Two ways to run:

lockstep (parameter ``lockstep:=true``, what the scenario runner uses)
    The runner publishes tug_msgs/SimStep(k) on /sim/step. The node buffers every input by
    the step it is stamped with (stamp = step * period, exact in nanoseconds) and computes
    k -> k+1 only once it holds, for step k: every required state input (e.g. the rope end
    wrenches for a vessel, the attachment kinematics for a rope), and the order stamped k if
    SimStep(k).ordered names this node's namespace. Then it publishes its outputs stamped
    k+1 and tug_msgs/StepDone(k+1) on /sim/step_done. Outputs go out before StepDone, but a
    peer never relies on that: it waits for the inputs themselves. The step-0 outputs are
    published at start-up, with StepDone(0) as the ready signal (repeated until the first
    trigger, so the runner need not be discovered first).

free-running (``lockstep:=false``, default for a node started by hand)
    A wall-clock timer steps at the exchange rate with the latest input of each kind.
"""
from __future__ import annotations

import dataclasses
import time
from typing import Any, Callable, Dict, List, Optional

from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from tug_msgs.msg import SimStep, StepDone

from sim_plumbing import cdr
from sim_plumbing import record_feed
from sim_plumbing import ros_common as rc


@dataclasses.dataclass
class StepInput:
    topic: str
    msg_type: Any
    # "state": needed every step in lockstep; "order": needed when SimStep.ordered names us,
    # otherwise applied from the step it arrives for.
    kind: str = "state"
    qos: Any = None
    # Hot inputs are taken raw and decoded by this function (sim_plumbing.cdr) into a light
    # tuple with a stamp_ns field; None: rclpy deserializes into the message class.
    decode: Optional[Callable[[bytes], Any]] = None


class SteppedNode(Node):
    """Base of the simulator nodes. Subclasses implement compute_step and publish_outputs."""

    def init_stepping(self, inputs: List[StepInput], ready: bool = True) -> None:
        """Declare exchange_rate and lockstep, subscribe the inputs. ready=False: the node
        sets self.ready_to_step later (e.g. a rope waiting for its ends' first positions)."""
        self.declare_parameter("exchange_rate", 50.0, rc.float_param(
            "Exchange steps per simulated second", 1.0, 1000.0, "Hz"))
        self.declare_parameter("lockstep", False, rc.text_param(
            "true: step on the scenario runner's /sim/step triggers; false: free-run on a wall-clock timer"))
        self.period_ns = rc.period_ns(self.get_parameter("exchange_rate").value)
        self.dt = self.period_ns * 1e-9
        self.lockstep = bool(self.get_parameter("lockstep").value)
        self.step_index = 0
        self.ready_to_step = ready
        self.inputs = inputs
        self._buffer: Dict[str, Dict[int, Any]] = {i.topic: {} for i in inputs}
        self._latest: Dict[str, Any] = {}
        self._triggers: Dict[int, cdr.TriggerIn] = {}
        self._triggered = False
        self.namespace_name = self.get_namespace().strip("/")
        self._wall_clock = Clock(clock_type=ClockType.STEADY_TIME)
        for spec in inputs:
            qos = spec.qos or (rc.COMMAND_QOS if spec.kind == "order" else rc.LATCHED_STATE_QOS)
            if spec.decode is None:
                self.create_subscription(spec.msg_type, spec.topic,
                                         lambda msg, s=spec: self._on_input(s, msg), qos)
            else:
                self.create_subscription(spec.msg_type, spec.topic,
                                         lambda data, s=spec: self._on_raw_input(s, data), qos, raw=True)
        if self.lockstep:
            self.done_pub = self.create_publisher(StepDone, rc.STEP_DONE_TOPIC, rc.PROTOCOL_QOS)
            self._done_cdr = cdr.StepDoneEncoder(self.get_fully_qualified_name())
            self.create_subscription(SimStep, rc.SIM_STEP_TOPIC, self._on_trigger_raw, rc.PROTOCOL_QOS, raw=True)
            # Wall-clock timers: with use_sim_time a ROS-time timer would wait for /clock forever.
            self._ready_timer = self.create_timer(0.2, self._announce_ready, clock=self._wall_clock)
        else:
            self.timer = self.create_timer(self.dt, self._on_timer, clock=self._wall_clock)

    def create_fed_publisher(self, msg_type, topic: str, qos) -> record_feed.FedPublisher:
        """A per-step output: publishes serialized messages and hands them to the scenario
        runner's recorder too, when the runner started this node with one."""
        return record_feed.FedPublisher(self.create_publisher(msg_type, topic, qos), record_feed.current())

    # -- to implement --------------------------------------------------------------------
    def step_of(self, spec: StepInput, msg: Any) -> int:
        """The step a message is stamped with (default: from its stamp)."""
        ns = msg.stamp_ns if spec.decode else rc.time_to_ns(msg.header.stamp)
        return ns // self.period_ns if ns % self.period_ns == 0 else -1

    def accept_input(self, spec: StepInput, msg: Any) -> bool:
        """Validate an input as it arrives; return False (and log why) to drop it."""
        return True

    def compute_step(self, inputs: Dict[str, Optional[Any]]) -> None:
        """Advance the model from step_index to step_index + 1 (inputs: topic -> msg or None)."""
        raise NotImplementedError

    def publish_outputs(self) -> None:
        """Publish the state of step_index."""
        raise NotImplementedError

    # -- machinery -----------------------------------------------------------------------
    def _on_raw_input(self, spec: StepInput, data: bytes) -> None:
        msg = cdr.decode_or_report(spec.decode, data, lambda why: self.get_logger().error(
            f"{spec.topic}: undecodable {spec.msg_type.__name__} dropped: {why}"))
        if msg is not None:
            self._on_input(spec, msg)

    def _on_trigger_raw(self, data: bytes) -> None:
        msg = cdr.decode_or_report(cdr.decode_sim_step, data, lambda why: self.get_logger().error(
            f"{rc.SIM_STEP_TOPIC}: undecodable SimStep dropped: {why}"))
        if msg is not None:
            self._on_trigger(msg)

    def _on_input(self, spec: StepInput, msg: Any) -> None:
        if not self.accept_input(spec, msg):
            return
        self._latest[spec.topic] = msg
        if not self.lockstep:
            return
        k = self.step_of(spec, msg)
        if k < 0:
            if spec.kind == "order":
                k = self.step_index  # unannounced order from outside the protocol: next step
            else:
                self.get_logger().error(f"{spec.topic}: stamp is not on the step grid, input dropped")
                return
        if spec.kind == "order" and k < self.step_index:
            k = self.step_index
        if spec.kind == "order" and k in self._buffer[spec.topic]:
            self.get_logger().warning(f"{spec.topic}: second order for step {k}; the later one wins")
        self._buffer[spec.topic][k] = msg
        self._advance()

    def _on_trigger(self, msg: cdr.TriggerIn) -> None:
        self._triggered = True
        if msg.step < self.step_index:
            return  # a trigger we already served (re-sent)
        self._triggers[msg.step] = msg
        self._advance()

    def _announce_ready(self) -> None:
        if self._triggered:
            self._ready_timer.cancel()
        elif self.ready_to_step:
            self._send_done(0, 0.0)

    def _ready(self, k: int) -> bool:
        trigger = self._triggers.get(k)
        if trigger is None or not self.ready_to_step:
            return False
        ordered = self.namespace_name in trigger.ordered
        for spec in self.inputs:
            if spec.kind == "state" and k not in self._buffer[spec.topic]:
                return False
            if spec.kind == "order" and ordered and k not in self._buffer[spec.topic]:
                return False
        return True

    def _advance(self) -> None:
        while self._ready(self.step_index):
            k = self.step_index
            del self._triggers[k]
            inputs = {}
            for spec in self.inputs:
                buf = self._buffer[spec.topic]
                inputs[spec.topic] = buf.get(k)
                for old in [s for s in buf if s <= k]:
                    del buf[old]
            t0 = time.perf_counter()
            try:
                self.compute_step(inputs)
            except Exception as exc:  # reported to the runner, which stops the run
                self.get_logger().error(f"step {k} failed: {exc}")
                self._send_done(k + 1, time.perf_counter() - t0, error=str(exc))
                raise
            self.step_index = k + 1
            self.publish_outputs()
            self._send_done(self.step_index, time.perf_counter() - t0)

    def _on_timer(self) -> None:
        if not self.ready_to_step:
            return
        inputs = {spec.topic: self._latest.get(spec.topic) for spec in self.inputs}
        for spec in self.inputs:
            if spec.kind == "order":
                self._latest.pop(spec.topic, None)  # an order applies once
        self.compute_step(inputs)
        self.step_index += 1
        self.publish_outputs()

    def _send_done(self, step: int, compute_time: float, error: str = "") -> None:
        self.done_pub.publish(self._done_cdr.encode(step * self.period_ns, step, compute_time, error))

    def stamp(self):
        return rc.step_time(self.step_index, self.period_ns)

    def stamp_ns(self) -> int:
        """Simulation time of the current step, ns (the stamp of its outputs)."""
        return self.step_index * self.period_ns
