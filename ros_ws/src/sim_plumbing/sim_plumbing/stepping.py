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

    Whose word counts: a node the runner started holds a private channel to it
    (sim_plumbing/step_channel.py): it steps on the channel's triggers only (a SimStep on the wire
    wakes it up; one the channel did not send is refused) and writes each StepDone there first,
    the copy the runner trusts. A node somebody else started has no channel and steps on the
    wire's SimStep. A second, different message for one step on a state input (or, without a
    channel, a second, different SimStep) means somebody else writes it: the node stops stepping
    and reports CONFLICT_MARK naming the publishers, and the runner stops the run as untrusted.

    Run identity: every run has a random id (parameter ``run_id``, handed over by the runner
    that starts the node; a node started by hand with no id joins the run of the first
    SimStep(0) it sees). A SimStep of another run, for a step the node is not at, or a
    duplicate is refused: logged (at most once a second per kind) and counted, and the count
    goes back to the runner in every StepDone (refused_messages). Inputs stamped more than
    MAX_LEAD_STEPS ahead are refused too, so a flood of future stamps cannot grow the buffers.
    An order the runner announced (SimStep.ordered) that the node then rejects still fills
    its slot: the node computes the step with its last valid order and says why.

free-running (``lockstep:=false``, default for a node started by hand)
    A wall-clock timer steps at the exchange rate with the latest input of each kind.
"""
from __future__ import annotations

import collections
import dataclasses
import time
from typing import Any, Callable, Dict, List, Optional, Tuple

from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.serialization import deserialize_message, serialize_message
from tug_msgs.msg import SimStep, StepDone

from sim_contract.node_params import STEPPING
from sim_plumbing import cdr
from sim_plumbing import local_bus
from sim_plumbing import record_feed
from sim_plumbing import ros_common as rc
from sim_plumbing import step_channel


# Inputs are stamped with the step they belong to; nothing legitimate is more than a step or two
# ahead of the node (outputs of step k+1 while it computes k). Farther ahead is refused, so a
# flood of future stamps from a stray publisher cannot grow the buffers without bound.
MAX_LEAD_STEPS = 100
# An order the runner announced but the node refused: the slot is filled, the last valid order held.
REJECTED_ORDER = object()
RESCUE_AFTER = 0.1  # s without a step before poll() takes what the executor may have missed
# Steps back for which a node keeps what it used (inputs, triggers): a different message for one
# of them arriving later is found out (the step was computed on a message that was not the only one).
KEPT_STEPS = 16


# Starts the error a node reports when it got two different messages for one step on one input
# (or two different triggers): one is not from the run's own publisher, and which one was used
# cannot be told. The node stops stepping; the runner stops the run as untrusted.
CONFLICT_MARK = "conflicting messages"


class RateLimitedLog:
    """Logs a kind of complaint at most once per `interval` s of wall time, with how many were
    suppressed since; counts every one. Keeps a flood of bad input from costing a log line (and
    the step's time) per message."""

    def __init__(self, logger, interval: float = 1.0):
        self.logger = logger
        self.interval = interval
        self.counts: collections.Counter = collections.Counter()
        self._last: Dict[str, float] = {}
        self._suppressed: collections.Counter = collections.Counter()

    def __call__(self, kind: str, text: str, level: str = "error") -> bool:
        """Count one; returns True if it was logged (callers may emit an event then)."""
        self.counts[kind] += 1
        now = time.monotonic()
        if now - self._last.get(kind, -1e9) < self.interval:
            self._suppressed[kind] += 1
            return False
        extra = self._suppressed.pop(kind, 0)
        self._last[kind] = now
        text += f" ({extra} more like it since the last report)" if extra else ""
        # one call site per severity: rclpy refuses a call site whose severity changes
        if level == "error":
            self.logger.error(text)
        elif level == "warning":
            self.logger.warning(text)
        else:
            self.logger.info(text)
        return True

    @property
    def total(self) -> int:
        return sum(self.counts.values())


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
    # Taken from a publisher in this process without DDS once one delivers (sim_plumbing.local_bus;
    # lockstep only). For the per-step outputs of the run's own nodes, never for orders.
    local: bool = False


class SteppedNode(Node):
    """Base of the simulator nodes. Subclasses implement compute_step and publish_outputs."""

    # Parameters that may change while the node runs (`ros2 param set`), adopted by
    # on_live_parameters from the next step on; every other parameter is fixed at start-up
    # (it shaped the model, its topics or the step protocol) and a change is refused.
    LIVE_PARAMETERS: Tuple[str, ...] = ()

    def init_stepping(self, inputs: List[StepInput], ready: bool = True) -> None:
        """Declare exchange_rate and lockstep, subscribe the inputs. ready=False: the node
        sets self.ready_to_step later (e.g. a rope waiting for its ends' first positions)."""
        rc.declare_table(self, STEPPING)
        self.period_ns = rc.period_ns(self.get_parameter("exchange_rate").value)
        self.dt = self.period_ns * 1e-9
        self.lockstep = bool(self.get_parameter("lockstep").value)
        self.run_id = str(self.get_parameter("run_id").value)
        self.complaints = RateLimitedLog(self.get_logger())  # refused protocol messages and inputs
        self.step_index = 0
        self.ready_to_step = ready
        self._heap_settled = False
        self.inputs = inputs
        self._buffer: Dict[str, Dict[int, Any]] = {i.topic: {} for i in inputs}
        # the state input held or used for each step (the last KEPT_STEPS), as (bytes, decoded): a
        # second one with other content for that step is a conflict (CONFLICT_MARK), a copy changes nothing
        self._prints: Dict[str, Dict[int, Tuple[bytes, Any]]] = {i.topic: {} for i in inputs}
        self.untrusted: Optional[str] = None  # why this node stopped stepping (a conflict)
        self._latest: Dict[str, Any] = {}
        self._triggers: Dict[int, cdr.TriggerIn] = {}
        self._used_triggers: Dict[int, Tuple[str, ...]] = {}  # step -> ordered of the trigger taken
        self.channel = None
        self._triggered = False
        self.namespace_name = self.get_namespace().strip("/")
        self._wall_clock = Clock(clock_type=ClockType.STEADY_TIME)
        self._taken: List[Tuple[Any, Callable]] = []  # (subscription, callback) for take_missed
        self._local_ends: List[Callable[[], None]] = []  # local_bus subscriptions, ended with the node
        self._off_dds: set = set()  # inputs taken locally, their DDS subscriptions destroyed
        self._progress = (0, time.monotonic())  # (step, wall time it was reached)
        self._last_rescue = 0.0
        self.rescued = 0  # messages the executor did not deliver, taken by poll()
        for spec in inputs:
            qos = spec.qos or (rc.COMMAND_SUB_QOS if spec.kind == "order" else rc.LATCHED_STATE_QOS)
            # No MESSAGE_LOST event handler: with rmw_fastrtps 8.4 (Jazzy) taking that event while
            # a flood loses samples deadlocks the node (an AB-BA lock order between the event
            # mutex and the DataReader's, ros2/rmw_fastrtps#890; measured here: 3 of 9 flooded
            # runs stalled, the node's thread blocked in get_sample_lost_status).
            if spec.decode is None:
                callback = lambda msg, s=spec: self._on_input(s, msg)  # noqa: E731
                sub = self.create_subscription(spec.msg_type, spec.topic, callback, qos)
            else:
                callback = lambda data, s=spec: self._on_raw_input(s, data)  # noqa: E731
                sub = self.create_subscription(spec.msg_type, spec.topic, callback, qos, raw=True)
            self._taken.append((sub, callback))
            if spec.local and self.lockstep and spec.kind == "state":
                self._local_ends.append(local_bus.subscribe(
                    sub.topic_name, lambda data, s=spec, sub=sub: self._on_local_input(s, sub, data)))
        if self.lockstep:
            # Started by the scenario runner: its private channel carries the triggers and takes
            # the answers; a SimStep on the wire is then only a wake-up (sim_plumbing/step_channel.py).
            self.channel = step_channel.for_node(self.get_fully_qualified_name())
            self._sent_triggers: Dict[int, Tuple[str, ...]] = {}  # step -> ordered, as the channel sent them
            self._latest_sent = -1   # the latest step the channel triggered
            self.late_wire_triggers = 0  # wire copies of this run's SimStep too far behind the channel to check
            self.done_pub = self.create_publisher(StepDone, rc.STEP_DONE_TOPIC, rc.PROTOCOL_QOS)
            self._done_cdr = cdr.StepDoneEncoder(self.get_fully_qualified_name(), self.run_id)
            self._taken.append((self.create_subscription(SimStep, rc.SIM_STEP_TOPIC, self._on_trigger_raw,
                                                         rc.PROTOCOL_QOS, raw=True), self._on_trigger_raw))
            # Wall-clock timers: with use_sim_time a ROS-time timer would wait for /clock forever.
            self._ready_timer = self.create_timer(0.2, self._announce_ready, clock=self._wall_clock)
            self._held: Optional[Tuple[int, float, bool]] = None  # (step, wall time first seen waiting, reported)
        else:
            self.timer = self.create_timer(self.dt, self._on_timer, clock=self._wall_clock)
        self.add_on_set_parameters_callback(self._on_set_parameters)

    def _on_set_parameters(self, params) -> SetParametersResult:
        refused = rc.fixed_parameters_refused(params, self.LIVE_PARAMETERS)
        if refused:
            return refused
        changes = {p.name: p.value for p in params}
        try:
            self.on_live_parameters(changes)
        except ValueError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        self.get_logger().info(f"parameter(s) {', '.join(f'{k}={v!r}' for k, v in changes.items())} in effect "
                               f"from step {self.step_index}")
        return SetParametersResult(successful=True)

    def on_live_parameters(self, changes: Dict[str, Any]) -> None:
        """Adopt new values of LIVE_PARAMETERS (their descriptors' ranges already checked);
        raise ValueError to refuse the whole change, leaving everything as it was."""

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
        msg = cdr.decode_or_report(spec.decode, data, lambda why: self.complaints(
            "undecodable " + spec.topic, f"{spec.topic}: undecodable {spec.msg_type.__name__} dropped: {why}"))
        if msg is not None:
            self._on_input(spec, msg, data)

    def _on_local_input(self, spec: StepInput, sub: Any, data: bytes) -> None:
        """An input's bytes from a node of this process (local_bus): the first one takes the
        input off DDS, whose copies would only repeat them."""
        if spec.topic not in self._off_dds:  # a set look-up per message, not a scan of the readers
            self._off_dds.add(spec.topic)
            self._taken = [(t, c) for t, c in self._taken if t is not sub]
            self.destroy_subscription(sub)
        if spec.decode is not None:
            self._on_raw_input(spec, data)
        else:
            self._on_input(spec, deserialize_message(data, spec.msg_type), data)

    def destroy_node(self):
        for end in getattr(self, "_local_ends", ()):
            end()
        return super().destroy_node()

    def _on_trigger_raw(self, data: bytes) -> None:
        msg = cdr.decode_or_report(cdr.decode_sim_step, data, lambda why: self.complaints(
            "undecodable trigger", f"{rc.SIM_STEP_TOPIC}: undecodable SimStep dropped: {why}"))
        if msg is None:
            return
        if self.channel is None:
            self._on_trigger(msg)
            return
        # the runner writes the trigger to the channel before it publishes: read it now, then the
        # wire's copy must be one the channel sent (anything else is somebody else's)
        self._take_channel()
        if msg.run_id == self.run_id and msg.step < self._latest_sent - MAX_LEAD_STEPS:
            # the wire's copy lags the channel when the executor falls behind a fast run: too late to
            # check (the triggers kept go back MAX_LEAD_STEPS), and nothing to act on either way
            self.late_wire_triggers += 1
            return
        if self._sent_triggers.get(msg.step) != msg.ordered or msg.run_id != self.run_id:
            # (no graph look to name the sender: a flood would pay one per message; the runner names
            # strangers on the protocol topics)
            self.complaints("unconfirmed trigger", f"{rc.SIM_STEP_TOPIC}: SimStep({msg.step}) of run '{msg.run_id}' "
                            "refused: not sent by this node's runner (not on its private channel)")

    def has_state_inputs(self, k: int) -> bool:
        """Whether every state input of step k is here (what a trigger of step k would wait for,
        but an order)."""
        return all(k in self._buffer[spec.topic] for spec in self.inputs if spec.kind == "state")

    def take_triggers(self) -> None:
        """Called by a runner that carries this node in its own process, right after it sent a
        step: the trigger is taken from the private channel now, not when the executor gets to
        the wire's SimStep (measured: 3-9 ms later with eight tows in one process, behind the
        events queued before it). The wire's copy, when it comes, is checked as ever."""
        if self.channel is not None and self.lockstep:
            self._take_channel()

    def _take_channel(self) -> None:
        """Triggers the runner sent on the private channel, taken in order."""
        for t in self.channel.triggers():
            self._sent_triggers[t.step] = t.ordered
            self._latest_sent = max(self._latest_sent, t.step)
            # the wire's copy may come late (an executor sitting on it): kept as long as an input may lead
            for old in [s for s in self._sent_triggers if s < t.step - MAX_LEAD_STEPS]:
                del self._sent_triggers[old]
            self._on_trigger(cdr.TriggerIn(t.step * self.period_ns, self.run_id, t.step, t.ordered))

    def publishers_of(self, topic: str) -> List[str]:
        """The nodes publishing `topic`, as the ROS graph names them (to name an intruder)."""
        try:
            infos = self.get_publishers_info_by_topic(topic)
        except Exception:  # noqa: BLE001 - naming is a courtesy; the refusal stands without it
            return ["(unknown)"]
        return sorted(f"{i.node_namespace.rstrip('/')}/{i.node_name}" for i in infos) or ["none"]

    def _conflict(self, topic: str, what: str) -> None:
        """A second, different message for a step: stop stepping, and say so to the runner now
        (whatever step it waits for) with the publishers of `topic` the graph shows."""
        self.complaints.counts["conflict"] += 1  # refused and counted like every refusal
        if self.untrusted is not None:
            return  # said once; the graph is not asked again for every further one
        text = f"{CONFLICT_MARK}: {topic}: {what} (publishers: {', '.join(self.publishers_of(topic))})"
        self.untrusted = text
        self.get_logger().error(f"{text}: this node stops stepping, its state cannot be trusted")
        if self.lockstep:
            self._send_done(self.step_index, 0.0, error=text)

    def _on_input(self, spec: StepInput, msg: Any, raw: Optional[bytes] = None) -> None:
        accepted = self.accept_input(spec, msg)
        if accepted:
            self._latest[spec.topic] = msg
        if not self.lockstep:
            return
        k = self.step_of(spec, msg)
        if k < 0:
            if spec.kind != "order":
                self.complaints("off-grid " + spec.topic, f"{spec.topic}: stamp is not on the step grid, input dropped")
                return
            k = self.step_index  # unannounced order from outside the protocol: next step
        if k > self.step_index + MAX_LEAD_STEPS:
            self.complaints("ahead " + spec.topic, f"{spec.topic}: input stamped for step {k}, more than "
                            f"{MAX_LEAD_STEPS} steps ahead of this node (step {self.step_index}): refused")
            return
        buf = self._buffer[spec.topic]
        if spec.kind == "state" and accepted:
            # one message per step from the run's publisher; a second, different one is a
            # stranger's (or the first was): refused, and the run cannot be trusted any more
            data = raw if raw is not None else serialize_message(msg)
            held = self._prints[spec.topic].get(k)
            if held is not None:
                # the bytes first (a DDS copy repeats them); then the content, because CDR's alignment
                # padding is not zeroed by the serializer: one message serialized twice can differ there
                if held[0] != data and held[1] != msg:
                    self._conflict(spec.topic, f"two different messages stamped step {k}")
                return  # a copy of what is held or was used: changes nothing
            if k < self.step_index:
                return  # for a step computed long ago: nothing to use it for
            self._prints[spec.topic][k] = (data, msg)
        if spec.kind == "order":
            k = max(k, self.step_index)
            if not accepted:
                # keep the step's slot filled (an announced order must not stall the step), but never
                # displace a valid order already there
                buf.setdefault(k, REJECTED_ORDER)
            else:
                if buf.get(k, REJECTED_ORDER) is not REJECTED_ORDER:
                    self.complaints("second order " + spec.topic,
                                    f"{spec.topic}: second order for step {k}; the later one wins", "warning")
                buf[k] = msg
        elif accepted:
            buf[k] = msg
        else:
            return
        if k == self.step_index:  # an input for a later step cannot make this one ready
            self._advance()

    def _on_trigger(self, msg: cdr.TriggerIn) -> None:
        if self.untrusted is not None:
            return
        if not self.run_id and msg.step == 0 and msg.run_id:
            self.run_id = msg.run_id  # started by hand: join the first run that starts
            self._done_cdr = cdr.StepDoneEncoder(self.get_fully_qualified_name(), self.run_id)
            self.get_logger().info(f"joined run {self.run_id}")
        if not msg.run_id or msg.run_id != self.run_id:
            self.complaints("foreign trigger", f"{rc.SIM_STEP_TOPIC}: SimStep({msg.step}) of run "
                            f"'{msg.run_id}' refused (this node is in run '{self.run_id}')")
            return
        used = self._used_triggers.get(msg.step)
        if used is not None and used != msg.ordered:
            # without a channel the wire is all there is: a different trigger for a step is a
            # stranger's, and the step may have been computed on it
            self._conflict(rc.SIM_STEP_TOPIC, f"two different SimStep({msg.step}) of this run (ordered "
                           f"{list(used)} and {list(msg.ordered)})")
            return
        if msg.step != self.step_index or msg.step in self._triggers:
            self.complaints("unexpected trigger", f"{rc.SIM_STEP_TOPIC}: SimStep({msg.step}) refused: this node "
                            f"is at step {self.step_index}" + (" and holds that trigger already"
                                                                 if msg.step in self._triggers else ""))
            return
        self._triggered = True
        self._triggers[msg.step] = msg
        self._used_triggers[msg.step] = msg.ordered
        for old in [s for s in self._used_triggers if s < msg.step - KEPT_STEPS]:
            del self._used_triggers[old]
        self._advance()

    def missing_inputs(self, k: int) -> List[str]:
        """What step k still waits for (the trigger, a state input, an announced order)."""
        trigger = self._triggers.get(k)
        if trigger is None:
            return [f"{rc.SIM_STEP_TOPIC} SimStep({k})"]
        missing = [] if self.ready_to_step else ["the node's own start-up"]
        ordered = self.namespace_name in trigger.ordered
        for spec in self.inputs:
            if k not in self._buffer[spec.topic] and (spec.kind == "state" or ordered):
                missing.append(f"{spec.topic} stamped {k}")
        return missing

    def poll(self) -> None:
        """Called by the spin loop after every round (not by a timer: see ros_common.take_missed).
        A lockstep node takes what its channel holds, and one that has not advanced for
        RESCUE_AFTER takes what its readers hold."""
        if not self.lockstep:
            return
        if self.channel is not None:
            self._take_channel()
        now = time.monotonic()
        if self.step_index != self._progress[0]:
            self._progress = (self.step_index, now)
            return
        if now - self._progress[1] > RESCUE_AFTER and now - self._last_rescue > RESCUE_AFTER:
            self._last_rescue = now
            taken = sum(rc.take_missed(sub, callback) for sub, callback in self._taken)
            if taken:
                self.rescued += taken
                # not a refusal: logged directly, so StepDone's refused count stays a count of refusals
                self.get_logger().warning(f"took {taken} message(s) the executor had not delivered (rclpy "
                                          f"EventsExecutor; {self.rescued} so far)")
        self._report_waiting()

    def _report_waiting(self) -> None:
        """A run stuck at this node's step names what the node waits for (the runner only knows
        who is silent): the trigger, or an input of the triggered step."""
        k = self.step_index
        if k not in self._triggers and not (self._triggered and self.ready_to_step):
            self._held = None
            return
        now = time.monotonic()
        if self._held is None or self._held[0] != k:
            self._held = (k, now, False)
            return
        _, since, reported = self._held
        if not reported and now - since > 5.0:
            self._held = (k, since, True)
            self.get_logger().warning(f"step {k}: waiting for {now - since:.0f} s for: "
                                      f"{', '.join(self.missing_inputs(k)) or 'nothing (a bug)'}")

    def _announce_ready(self) -> None:
        if self._triggered:
            self._ready_timer.cancel()
        elif self.ready_to_step:
            if not self._heap_settled:   # before the run's clock starts (it waits for every node's ready)
                self._heap_settled = True
                rc.settle_heap()
            self._send_done(0, 0.0)

    def _ready(self, k: int) -> bool:
        trigger = self._triggers.get(k)
        if trigger is None or not self.ready_to_step or self.untrusted is not None:
            return False
        if not self.has_state_inputs(k):
            return False
        return self.namespace_name not in trigger.ordered or all(
            k in self._buffer[spec.topic] for spec in self.inputs if spec.kind == "order")

    def _advance(self) -> None:
        with local_bus.stepping():  # what this node's steps post reaches the others after them
            self._advance_steps()

    def _advance_steps(self) -> None:
        while self._ready(self.step_index):
            k = self.step_index
            del self._triggers[k]
            inputs = {}
            for spec in self.inputs:
                buf = self._buffer[spec.topic]
                msg = buf.get(k)
                inputs[spec.topic] = None if msg is REJECTED_ORDER else msg
                for old in [s for s in buf if s <= k]:
                    del buf[old]
                prints = self._prints[spec.topic]
                for old in [s for s in prints if s < k - KEPT_STEPS]:
                    del prints[old]
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
        if self.channel is not None:  # first on the channel, the runner's trusted copy
            try:
                self.channel.send_answer(step_channel.Answer(step, compute_time, not error, self.complaints.total,
                                                             error))
            except step_channel.ChannelBroken as exc:
                self.complaints("channel", f"the runner's channel is gone ({exc}); the runner has ended")
        self.done_pub.publish(self._done_cdr.encode(step * self.period_ns, step, compute_time, error,
                                                    self.complaints.total))

    def stamp(self):
        return rc.step_time(self.step_index, self.period_ns)

    def stamp_ns(self) -> int:
        """Simulation time of the current step, ns (the stamp of its outputs)."""
        return self.step_index * self.period_ns
