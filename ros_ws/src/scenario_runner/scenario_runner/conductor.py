"""Runs a validated scenario: starts the nodes, owns /clock and the step protocol, sends the
timed orders, watches the nodes and stops everything cleanly.

Step protocol (see sim_plumbing/stepping.py and the README): for k = 0, 1, ...
  1. orders due at step k go out stamped k on /<vessel>/command and /<rope>/winch;
  2. /clock is set to k*T and tug_msgs/SimStep(k, ordered=[namespaces with an order]) is sent;
  3. each node computes k -> k+1 from inputs stamped k and answers StepDone(k+1);
  4. once every node has answered, step k+1 starts (lockstep) or waits for its wall-clock
     time (realtime; lateness is measured and reported).
SimStep goes to the nodes this runner started on their private channels first, and only their
channels' answers count (sim_plumbing/step_channel.py); the wire's copies are for observers,
external nodes and the recording. Strangers: docs/step-protocol.md, threat model.
"""
from __future__ import annotations

import collections
import dataclasses
import math
import os
import secrets
import signal
import sys
import time
from typing import Callable, Deque, Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np
import rclpy
from rclpy.node import Node
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from nav_msgs.msg import Odometry
from tug_msgs.msg import ScenarioEvent, SimStep, StepDone, VesselCommand, WinchCommand

from sim_contract import topics as T
from sim_math.rotations import yaw_from_quaternion
from scenario_format.scenario import Scenario
from sim_plumbing import cdr
from sim_plumbing import record_feed
from sim_plumbing import shm_hygiene
from sim_plumbing import step_channel
from sim_plumbing import ros_common as rc
from sim_plumbing.stepping import CONFLICT_MARK, MAX_LEAD_STEPS, RESCUE_AFTER, RateLimitedLog
from scenario_runner.order_owner import (ANCHOR_LET_GO, ANCHOR_HEAVE_UP, ANCHOR_NO_CHANGE, HAND_BACK, WINCH,
                                         OrderOwners, VesselOrder, WinchOrder, describe)
from scenario_runner.node_processes import (DEFAULT_LAYOUT, LAYOUTS, NodeProcesses, cores, default_group_count, in_process_nodes,
                                            node_groups)
from scenario_runner.run_nodes import (NodeSpec, RunError, external_outputs, instrument_specs, node_specs,
                                      per_step_outputs)


# a scripted anchor order as VesselCommand takes it
SCRIPT_ANCHOR = {"let_go": ANCHOR_LET_GO, "heave_up": ANCHOR_HEAVE_UP}


class Untrusted(RunError):
    """The run's result cannot be trusted: a stranger publishes one of its per-step state topics,
    a node got two different messages for one step, or the step count does not match what a node
    published. Named; the run stops (exit 5)."""



class DomainInUse(RunError):
    """Another run, or nodes left by one, are on this ROS domain: refused before anything starts
    or, if seen only once this run's nodes are up, before step 0."""


class Interrupted(Exception):
    """Ctrl-C or SIGTERM: the run stops, the recording is finalised (signal number in args[0])."""


# s of discovery before the domain check: a new process sees a running node within 0.03-2.9 s
# (30 trials on this machine; Fast DDS's announcement period is 3 s); with 1 s a run already
# on the domain went unseen now and then
DOMAIN_DISCOVERY_WAIT = 3.0
# where the domain is known to be one's own (the test suite reserves one per test), the wait can
# be shortened: TUGSIM_DOMAIN_CHECK_WAIT=<s>
DOMAIN_CHECK_WAIT_VARIABLE = "TUGSIM_DOMAIN_CHECK_WAIT"


def domain_discovery_wait() -> float:
    """s of discovery before the domain check: DOMAIN_DISCOVERY_WAIT, or the environment's
    TUGSIM_DOMAIN_CHECK_WAIT (a number of seconds >= 0; RunError naming it otherwise)."""
    text = os.environ.get(DOMAIN_CHECK_WAIT_VARIABLE)
    if text is None:
        return DOMAIN_DISCOVERY_WAIT
    try:
        wait = float(text)
    except ValueError:
        wait = math.nan
    if not (math.isfinite(wait) and wait >= 0.0):
        raise RunError(f"{DOMAIN_CHECK_WAIT_VARIABLE}={text!r}: expected a number of seconds >= 0 "
                       f"(unset: {DOMAIN_DISCOVERY_WAIT:g} s)")
    return wait
# the channel answers kept per node to check the wire's copies against; a copy for an older step
# comes too late to be checked (late_wire_copies)
ANSWERS_KEPT = 64
# s between looks at the ROS graph for external nodes that have left it (run(external=...))
GRAPH_CHECK_PERIOD = 0.25
# Paced, the graph look waits for idle time before a step, not the inside of a step, where in one
# process it made every 13th step of eight tows late: at least this much idle time, and 1.5 times
# the longest of its last looks (5-8 ms with eight tows' 72 per-step topics: with a fixed 4 ms the
# looks that found 4-7 ms made their next step 1-4 ms late). It is done inside a step only when it
# has found no such time for this long past its due time.
GRAPH_CHECK_IDLE = 0.004
GRAPH_CHECK_OVERDUE = 1.0


def new_run_id() -> str:
    return secrets.token_hex(8)


@dataclasses.dataclass
class RunStats:
    steps_done: int = 0
    wall_time: float = 0.0
    overruns: int = 0  # realtime: steps finished after their wall-clock deadline
    overrun_steps: List[Tuple[int, float]] = dataclasses.field(default_factory=list)  # the first: (step, s late)
    first_step: float = float("nan")  # realtime: s step 0 took (before the clock: Session.step)
    lateness: List[float] = dataclasses.field(default_factory=list)  # realtime: s behind schedule per step
    round_trips: List[float] = dataclasses.field(default_factory=list)  # s from SimStep to last StepDone
    compute_times: Dict[str, List[float]] = dataclasses.field(default_factory=dict)  # node -> s per step
    cpu_time: float = float("nan")  # s of CPU of every process of the run (runner and nodes) while stepping
    run_id: str = ""
    refused: Dict[str, int] = dataclasses.field(default_factory=dict)  # why -> StepDones the runner refused
    node_refused: Dict[str, int] = dataclasses.field(default_factory=dict)  # node -> messages it refused
    late_wire_copies: int = 0  # StepDone wire copies too far behind the channels to be checked
    rescued: int = 0  # StepDones the executor held back, taken directly (ros_common.take_missed)
    external: List[str] = dataclasses.field(default_factory=list)  # nodes of the run started by somebody else
    strangers: Dict[str, int] = dataclasses.field(default_factory=dict)  # stranger on a protocol topic -> step seen
    outputs_checked: int = 0  # per-step output topics whose recorded count matched the steps
    never_fired: List[str] = dataclasses.field(default_factory=list)  # state-triggered events whose `when` never held


class Conductor(Node):
    """The runner's own node: /clock, /sim/step, orders and events out; StepDone in."""

    def __init__(self, sc: Scenario, node_names: List[str], recorder=None, run_id: Optional[str] = None,
                 external: Sequence[str] = (), **kwargs):
        super().__init__("scenario_runner", **kwargs)
        # node name -> the runner's end of its private channel (step_channel), set once the nodes
        # are started: the only source of their answers the runner trusts
        self.channels: Dict[str, object] = {}
        self.broken_channels: Dict[str, tuple] = {}   # node -> (when, why) its channel broke
        self.confirmed: Dict[str, Dict[int, Tuple[bool, str]]] = {}  # node -> step -> (ok, error) on its channel
        self.confirmed_latest: Dict[str, int] = {}  # node -> the latest step its channel answered
        # wire copies of channel answers more than ANSWERS_KEPT steps behind the channel: not checkable
        self.late_wire_copies = 0
        self.last_answer: Dict[str, int] = {}  # node -> the last step it answered (channel, or wire if external)
        self.wire_copies: Dict[str, collections.Counter] = {}  # node with a channel -> step -> its StepDones on the wire
        self.strangers: Dict[str, int] = {}  # "node X (publishes T)" on a protocol topic -> step first seen
        # nodes whose answers come on the wire only (external, or started without a channel): each
        # answers a step once, so a second answer in its name is somebody else's
        self.wire_only = set(external)
        # nodes of the run this runner did not start (--external): expected on the domain, and
        # their ready signal counts before they have joined the run (started without a run_id)
        self.external = set(external)
        self.created = time.monotonic()
        self.recorder = recorder
        self.sc = sc
        self.run_id = run_id or new_run_id()
        self.period_ns = rc.period_ns(sc.exchange_rate)
        self.expected = set(node_names)
        self.done: Dict[int, set] = {}
        self.awaited = 0  # the step whose StepDone is due: 0 before the first trigger, then k+1
        self.refused: collections.Counter = collections.Counter()  # why -> StepDones refused
        self.node_refused: Dict[str, int] = {}  # node -> messages it reports having refused
        self.complaints = RateLimitedLog(self.get_logger())
        self.failures: List[str] = []
        self.compute_times: Dict[str, List[float]] = {n: [] for n in node_names}
        self.clock_pub = self.create_publisher(Clock, T.CLOCK, rc.CLOCK_QOS)
        self.step_pub = self.create_publisher(SimStep, rc.SIM_STEP_TOPIC, rc.PROTOCOL_QOS)
        self.event_pub = self.create_publisher(ScenarioEvent, rc.EVENTS_TOPIC, rc.EVENTS_QOS)
        self.cmd_pubs = {v.name: self.create_publisher(VesselCommand, T.vessel_topic(v.name, T.COMMAND), rc.COMMAND_QOS)
                         for v in sc.vessels}
        self.winch_pubs = {r.name: self.create_publisher(WinchCommand, T.rope_topic(r.name, T.WINCH), rc.COMMAND_QOS)
                           for r in sc.ropes if r.layout == "winch"}
        # raw: the answers are recorded as received and decoded once, here
        self.done_sub = self.create_subscription(StepDone, rc.STEP_DONE_TOPIC, self._on_done_raw, rc.PROTOCOL_QOS,
                                                 raw=True)
        self.rescued = 0  # StepDones the executor did not deliver, taken in wait_for (rc.take_missed)
        # Orders: timed events by step, state-triggered events armed in file order (_orders_at);
        # who owns each control, and what each vessel and winch holds (order_owner.py)
        self.owners = OrderOwners({v.name: (float(v.initial.engine_order), math.radians(v.initial.steering_deg))
                                   for v in sc.vessels}, winches=list(self.winch_pubs),
                                  manned=[v.name for v in sc.vessels if v.manned])
        self.timed: Dict[int, List[int]] = {}
        for i, ev in enumerate(sc.events):
            if ev.time is not None:
                self.timed.setdefault(int(round(ev.time * sc.exchange_rate)), []).append(i)
        self.fired: set = set()
        self.triggered = [i for i, ev in enumerate(sc.events) if ev.when is not None]
        # the state of each vessel a trigger watches: its odometry, the step's own
        self.watched = sorted({sc.events[i].when.vessel for i in self.triggered})
        self.vessel_state: Dict[str, Tuple[int, float, float, float]] = {}  # stamp ns, yaw unwrapped, speed, u
        self.heading_since: Dict[Tuple[str, int], float] = {}  # (vessel, step) -> unwrapped yaw then
        self._since_steps = {(sc.events[i].when.vessel, int(round(sc.events[i].when.since * sc.exchange_rate)))
                             for i in self.triggered if sc.events[i].when.heading_change_deg is not None}
        self.odom_subs = [self.create_subscription(Odometry, T.vessel_topic(name, T.ODOM), lambda m, n=name: self._on_odom(n, m),
                                                   rc.LATCHED_STATE_QOS) for name in self.watched]
        # Vessels steered by a lockstep autopilot get its order stamped k at every step k.
        self.piloted = sorted(a.vessel for a in sc.autopilots)
        self._watch_orders()

    def _on_done_raw(self, data: bytes) -> None:
        if self.recorder:
            self.recorder.record(rc.STEP_DONE_TOPIC, data)
        msg = cdr.decode_or_report(cdr.decode_step_done, data, lambda why: self.get_logger().error(
            f"{rc.STEP_DONE_TOPIC}: undecodable StepDone dropped: {why}"))
        if msg is not None:
            self._on_done(msg)

    def _publish(self, publisher, topic: str, data: bytes) -> None:
        """The same bytes go out and into the recording."""
        publisher.publish(data)
        if self.recorder:
            self.recorder.record(topic, data)

    def _refuse(self, why: str, msg: cdr.DoneIn, detail: str, where: str = rc.STEP_DONE_TOPIC) -> None:
        self.refused[why] += 1
        self.complaints(why, f"{where}: StepDone({msg.step}) from '{msg.node}' refused: {detail}")

    def take_answers(self) -> int:
        """Answers the nodes sent on their channels since the last look, counted; how many."""
        n = 0
        for node, channel in self.channels.items():
            for a in channel.answers():
                n += 1
                confirmed = self.confirmed.setdefault(node, {})
                confirmed[a.step] = (a.ok, a.error)
                self.confirmed_latest[node] = max(a.step, self.confirmed_latest.get(node, a.step))
                for old in [s for s in confirmed if s < a.step - ANSWERS_KEPT]:
                    del confirmed[old]
                self._count(cdr.DoneIn(a.step * self.period_ns, self.run_id, node, a.step, a.compute_time, a.ok,
                                       a.refused, a.error), where=f"the channel of {node}")
        return n

    def send_triggers(self, k: int, ordered: List[str]) -> None:
        """SimStep(k) to every node on its channel (before the wire's copy: a node that reads a
        SimStep on the wire finds the channel's first)."""
        for node, channel in self.channels.items():
            if node in self.broken_channels:
                continue
            try:
                channel.send_trigger(k, ordered)
            except step_channel.ChannelBroken as exc:
                # most often the node's process has died: the wait that follows names that (exit
                # code, log); a channel gone with the process alive stops the run a second later
                self.broken_channels[node] = (time.monotonic(), f"node {node}: its channel is gone ({exc}) while "
                                                                f"sending step {k}")

    def _on_done(self, msg: cdr.DoneIn) -> None:
        """A StepDone on the wire. A node with a channel answers there: its StepDone on the wire is
        an observers' copy, checked against the channel (anything else is somebody else's, refused);
        an external node has only the wire."""
        if msg.run_id != self.run_id:
            if not msg.run_id and msg.step == 0 and msg.node in self.external and self.awaited <= 1:
                # an external node started without run_id announces itself; it joins this run
                # with the first SimStep(0) (sim_plumbing.stepping) and answers with its id
                self.done.setdefault(0, set()).add(msg.node)
                return
            return self._refuse("another run", msg, f"run '{msg.run_id}', this run is '{self.run_id}'")
        if msg.node not in self.expected:
            return self._refuse("not in the run", msg, f"nodes of this run are {sorted(self.expected)}")
        if msg.node in self.channels:
            self.take_answers()  # the node writes its channel before it publishes
            if msg.step < self.confirmed_latest.get(msg.node, 0) - ANSWERS_KEPT:
                # the wire's copies lag the channel when the executor falls behind a fast run (seen:
                # 900 steps behind at 1000 steps/s): too late to check, so not refused as a
                # stranger's; it is not used either way (the channel's answer was)
                self.late_wire_copies += 1
                return
            if self.confirmed.get(msg.node, {}).get(msg.step) != (msg.ok, msg.error):
                said = self.confirmed.get(msg.node, {}).get(msg.step)
                return self._refuse("not the node's", msg, f"{msg.node} said {_said(said)} for that step on its own "
                                    f"channel, the wire {_said((msg.ok, msg.error))}: somebody else's answer in its "
                                    "name")
            copies = self.wire_copies.setdefault(msg.node, collections.Counter())
            copies[msg.step] += 1
            for old in [s for s in copies if s < msg.step - ANSWERS_KEPT]:
                del copies[old]
            if msg.step >= 1 and copies[msg.step] > 1:
                # the node publishes each answer once (only its ready signal repeats): a second copy
                # is somebody else's, harmless as it says what the channel said, refused and counted
                return self._refuse("not the node's", msg, "a second copy on the wire of an answer the node gives "
                                    "once")
            return  # the node's own answer, copied on the wire for observers
        if msg.step >= 1 and msg.step <= self.last_answer.get(msg.node, -1) and msg.node in self.wire_only:
            # a node without a channel answers each step once: a second answer for a step is
            # somebody else's in its name, and which one the run went on cannot be told
            self.failures.append(f"{CONFLICT_MARK}: two StepDone({msg.step}) of {msg.node} (no private channel) "
                                 f"(publishers of {rc.STEP_DONE_TOPIC}: "
                                 f"{', '.join(self.publishers_of(rc.STEP_DONE_TOPIC))}): somebody else answers in "
                                 "its name")
            return
        self._count(msg)

    def publishers_of(self, topic: str) -> List[str]:
        return sorted(_node_of(i) for i in self.get_publishers_info_by_topic(topic)) or ["none"]

    def _count(self, msg: cdr.DoneIn, where: str = rc.STEP_DONE_TOPIC) -> None:
        """Only an answer of a node of the run for the step now due, once; a failure whatever the
        step (a node that stopped on a conflict says so at once)."""
        self.node_refused[msg.node] = msg.refused
        if not msg.ok and msg.step >= self.awaited - 1:
            self.failures.append(f"{msg.node} failed at step {msg.step}: {msg.error}")
            return  # the run stops on it: no step bookkeeping
        if msg.step == 0 and self.awaited <= 1:
            self.done.setdefault(0, set()).add(msg.node)  # the ready signal, repeated until triggered
            return
        if msg.step != self.awaited:
            return self._refuse("step not triggered" if msg.step > self.awaited else "late or duplicate", msg,
                                f"the step due is {self.awaited}", where)
        answered = self.done.setdefault(msg.step, set())
        if msg.node in answered:
            return self._refuse("duplicate", msg, "this node has answered that step already", where)
        answered.add(msg.node)
        self.last_answer[msg.node] = msg.step
        self.compute_times[msg.node].append(msg.compute_time)

    def participants_beyond(self, own: Iterable[str]) -> List[str]:
        """Step-protocol participants on this domain beyond this runner and one of each `own`
        node: another runner publishing /sim/step, nodes taking it or answering /sim/step_done
        that are not `own`, and a second node under an `own` name. Before the start `own` is the
        run's external nodes (anything else is a run in progress, or nodes a killed run left);
        once this run's nodes are up, all of them (a stranger the first look missed: discovery
        can take seconds). Their triggers, answers and latched outputs would mix with this run's."""
        me = self.get_fully_qualified_name()
        own = set(own)
        found = []
        for topic, kind, infos, allowed in (
                (rc.SIM_STEP_TOPIC, "publishes", self.get_publishers_info_by_topic(rc.SIM_STEP_TOPIC), {me}),
                (T.CLOCK, "publishes", self.get_publishers_info_by_topic(T.CLOCK), {me}),
                (rc.SIM_STEP_TOPIC, "takes", self.get_subscriptions_info_by_topic(rc.SIM_STEP_TOPIC), own),
                (rc.STEP_DONE_TOPIC, "answers on", self.get_publishers_info_by_topic(rc.STEP_DONE_TOPIC), own)):
            what = "scenario runner" if kind == "publishes" else "node"
            for node, count in sorted(collections.Counter(_node_of(i) for i in infos).items()):
                if node not in allowed:
                    found.append(f"{what} {node} ({kind} {topic})")
                elif count > 1:
                    found.append(f"{count} nodes named {node} ({kind} {topic}): one is not this run's")
        return found

    def state_intruders(self, owners: Dict[str, str]) -> List[str]:
        """Publishers of the run's per-step state topics (topic -> owner node) other than one
        owner each: a stranger's message there could be taken for the owner's (a vessel moved
        41.8 m sideways by a republished towline wrench)."""
        found = []
        for topic, owner in sorted(owners.items()):
            for node, count in sorted(collections.Counter(_node_of(i) for i in
                                                          self.get_publishers_info_by_topic(topic)).items()):
                if "_UNKNOWN_" in node:
                    continue  # its name is not discovered yet: named at the next look
                if node != owner:
                    found.append(f"node {node} publishes {topic} (a per-step state topic of {owner})")
                elif count > 1:
                    found.append(f"{count} nodes named {node} publish {topic}: one is not this run's")
        return found

    def note_protocol_strangers(self, k: int) -> None:
        """Publishers on /sim/step, /clock or /sim/step_done that are not this run's (after step 0:
        the look before it refused them): their messages are refused (run id, channels), and they
        are named once in the log and in the summary."""
        for found in self.participants_beyond(self.expected):
            if "_UNKNOWN_" in found or "(takes " in found or found in self.strangers:
                continue  # a subscriber only reads
            self.strangers[found] = k
            self.get_logger().warning(f"a stranger on the step protocol's topics since step {k}: {found}; its "
                                      "messages are refused (run id, the nodes' private channels)")

    def check_domain(self, executor, wait: Optional[float] = None) -> None:
        """Refuse to start on a domain where another run (or its leftover nodes) is present,
        after `wait` s of discovery (None: domain_discovery_wait())."""
        wait = domain_discovery_wait() if wait is None else wait
        while time.monotonic() < self.created + wait:
            executor.spin_once(timeout_sec=0.02)
        self.refuse_if_found(executor, lambda: self.participants_beyond(self.external))

    def refuse_if_found(self, executor, look: Callable[[], List[str]], when: str = "") -> None:
        """DomainInUse naming what look() finds (after a moment for names still unknown)."""
        found = look()
        # endpoints are discovered before the names of their nodes: give the names a moment
        deadline = time.monotonic() + 3.0
        while any("_UNKNOWN_" in f for f in found) and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
            found = look()
        if found:
            domain = os.environ.get("ROS_DOMAIN_ID", "0")
            raise DomainInUse(
                f"ROS_DOMAIN_ID={domain} is in use by another run{when}: {'; '.join(found)}. Stop that run (or its "
                f"leftover nodes), or start this one on another domain, e.g. ROS_DOMAIN_ID={(int(domain) + 1) % 101}")

    def _on_odom(self, name: str, msg: Odometry) -> None:
        """The watched vessel's state: yaw unwrapped step by step, speed over ground, headway."""
        stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        prev = self.vessel_state.get(name)
        if prev is not None and stamp <= prev[0]:
            return  # a repeat (transient local) or out of order: the state of that step is known
        q = msg.pose.pose.orientation
        yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
        if prev is not None:
            yaw = prev[1] + math.remainder(yaw - prev[1], 2.0 * math.pi)
        lin = msg.twist.twist.linear
        self.vessel_state[name] = (stamp, yaw, math.hypot(lin.x, lin.y), lin.x)
        step = int(round(stamp / self.period_ns))
        if (name, step) in self._since_steps:
            self.heading_since[(name, step)] = yaw

    def states_needed(self, k: int) -> List[str]:
        """The watched vessels whose state of step k is not here yet (empty once every trigger
        has fired)."""
        if len(self.fired) == len(self.sc.events) or not self.watched:
            return []
        stamp = k * self.period_ns
        return [n for n in self.watched if self.vessel_state.get(n, (-1,))[0] < stamp]

    def _trigger_met(self, trigger, k: int) -> bool:
        stamp, yaw, speed, surge = self.vessel_state[trigger.vessel]
        if trigger.heading_change_deg is not None:
            ref = self.heading_since.get((trigger.vessel, int(round(trigger.since * self.sc.exchange_rate))))
            if ref is None:
                return False  # before `since`
            change = math.radians(trigger.heading_change_deg)
            return math.copysign(1.0, change) * (yaw - ref) >= abs(change)
        if trigger.speed_below is not None:
            return speed < trigger.speed_below
        if trigger.speed_above is not None:
            return speed > trigger.speed_above
        return surge < trigger.surge_below

    def _orders_at(self, k: int) -> Dict[str, object]:
        """The orders of step k (namespace -> VesselOrder or WinchOrder): its timed events, then
        the state-triggered events armed (every event listed before fired) whose condition the
        state of step k meets, in file order. Each event sets only the controls it names and the
        script owns (order_owner.py); the rest keep what the vessel holds: one order per namespace
        per step."""
        events = self.sc.events
        firing = list(self.timed.get(k, []))
        self.fired.update(firing)
        for i in self.triggered:
            if i in self.fired:
                continue
            if any(j not in self.fired for j in range(i)) or not self._trigger_met(events[i].when, k):
                break  # not armed, or not met: the events after it wait too
            self.fired.add(i)
            firing.append(i)
            self.event(k, "trigger", events[i].when.vessel, f"events[{i}]: {events[i].when.describe()}")
        out: Dict[str, object] = {}
        for i in sorted(firing, key=lambda j: (events[j].time if events[j].time is not None else k / self.sc.exchange_rate, j)):
            ev = events[i]
            if ev.vessel is not None:
                order, notes = self.owners.script_vessel(
                    ev.vessel, f"events[{i}]", engine=ev.engine_order,
                    helm=None if ev.steering_deg is None else math.radians(ev.steering_deg),
                    anchor=None if ev.anchor is None else SCRIPT_ANCHOR[ev.anchor])
                earlier = out.get(ev.vessel)
                if order is not None and earlier is not None and order.anchor == ANCHOR_NO_CHANGE:
                    order.anchor = earlier.anchor  # two events for one vessel in one step: both count
            else:
                order, notes = self.owners.script_winch(ev.rope, f"events[{i}]", ev.payout_rate)
            for note in notes:
                self.event(k, note.kind, note.target, note.detail, note.value)
            if order is not None:
                out[ev.vessel or ev.rope] = order
        return out

    # -- orders from outside the script (order_owner.py) -------------------------------------
    def _watch_orders(self) -> None:
        """Subscribe the order topics of every vessel and winch the script may order (not
        prescribed, not steered by the scenario's autopilot), raw, and /scenario/events for
        hand-back requests: orders that are not this conductor's own are somebody else's."""
        self.own_sent: Dict[str, collections.deque] = {}  # topic -> bytes of own orders not yet seen back
        self.outside: List[tuple] = []  # outside orders and hand-backs, in arrival order, decided at the next step
        self.order_topics: Dict[str, str] = {}  # topic -> vessel or rope
        self._who_cache: Dict[str, Tuple[int, float, str]] = {}  # topic -> (publishers, when, who)
        for v in self.sc.vessels:
            if v.motion is None and v.name not in self.piloted:
                self.order_topics[T.vessel_topic(v.name, T.COMMAND)] = v.name
        for rope in self.winch_pubs:
            self.order_topics[T.rope_topic(rope, T.WINCH)] = rope
        self.order_subs = [self.create_subscription(
            WinchCommand if target in self.winch_pubs else VesselCommand, topic,
            lambda data, topic=topic: self._on_order_raw(topic, data), rc.COMMAND_SUB_QOS, raw=True)
            for topic, target in self.order_topics.items()]
        self.hand_back_sub = self.create_subscription(ScenarioEvent, rc.EVENTS_TOPIC, self._on_event,
                                                      rc.EVENTS_QOS)

    def _on_order_raw(self, topic: str, data: bytes) -> None:
        own = self.own_sent.get(topic)
        if own and data in own:
            while own.popleft() != data:
                pass  # orders arrive in the order they were sent: older ones are not coming back
            return
        target = self.order_topics[topic]
        decode = cdr.decode_winch_command if target in self.winch_pubs else cdr.decode_vessel_command
        msg = cdr.decode_or_report(decode, data, lambda why: None)  # the node refuses it, and says so
        if msg is not None and _takes(msg):
            self.outside.append((target, msg, self._who(topic)))

    def _on_event(self, msg: ScenarioEvent) -> None:
        if msg.kind == HAND_BACK:
            controls = [c.strip() for c in msg.detail.split(",") if c.strip()]
            self.outside.append((msg.target, controls, msg.source or "an outside node"))

    def _who(self, topic: str) -> str:
        """The nodes other than this one that publish topic: who gave the order, if one. Asked
        of the graph at most once a second per topic, and when its publisher count changes (a
        flood of orders must not cost a graph query each)."""
        count, now = self.count_publishers(topic), time.monotonic()
        cached = self._who_cache.get(topic)
        if cached is not None and cached[0] == count and now < cached[1] + 1.0:
            return cached[2]
        me = self.get_fully_qualified_name()
        others = sorted({_node_of(i) for i in self.get_publishers_info_by_topic(topic)} - {me})
        others = [n for n in others if "_UNKNOWN_" not in n]
        who = ("an outside node" if not others else others[0] if len(others) == 1 else
               f"one of {', '.join(others)}")
        self._who_cache[topic] = (count, now, who)
        return who

    def _take_outside(self, k: int) -> set:
        """Decide on the outside orders and hand-backs that came in since the last step, in
        arrival order, announced stamped k; the targets whose held orders must be confirmed."""
        confirm = set()
        items, self.outside = self.outside, []
        for target, what, who in items:
            if isinstance(what, list):
                if target not in self.owners.held and target not in self.owners.winches:
                    self.get_logger().warning(f"hand-back for '{target}' by {who}: not a vessel or winch of the run")
                    continue
                notes = self.owners.hand_back(target, what, who)
            else:
                stamp_step = what.stamp_ns // self.period_ns
                if stamp_step > k + MAX_LEAD_STEPS:
                    continue  # the node refuses it: too far ahead
                if isinstance(what, cdr.WinchCommandIn):
                    notes, again = self.owners.outside_winch(target, WinchOrder(*what[1:]), who, stamp_step)
                else:
                    notes, again = self.owners.outside_vessel(
                        target, VesselOrder(what.engine_order, what.steering_angle, what.anchor), who, stamp_step)
                if again:
                    confirm.add(target)
            for note in notes:
                self.event(k, note.kind, note.target, note.detail, note.value)
        return confirm

    def announce_manned(self, k: int) -> None:
        """The manned vessels, said at the start: every order of theirs is a person's."""
        for i, v in enumerate(self.sc.vessels):
            if v.manned:
                self.event(k, "manual_order", v.name, f"{v.name} is manned (vessels[{i}].manned): engine, helm and "
                           "anchor are the crew's; the script gives it no orders")

    def order_publishers(self):
        return list(self.cmd_pubs.values()) + list(self.winch_pubs.values())

    def own_readers(self, publisher) -> int:
        """Readers of an order publisher that are this conductor's own (watching the topic)."""
        return 1 if publisher.topic_name in self.order_topics else 0

    def send_step(self, k: int) -> None:
        stamp = rc.step_time(k, self.period_ns)
        if self.recorder:
            self.recorder.log_time_ns = k * self.period_ns
        confirm = self._take_outside(k)
        orders = self._orders_at(k)  # a scripted order carries the held values: it confirms them too
        confirm -= set(orders)
        for target in confirm:
            orders[target] = self.owners.confirmation(target)
        ordered = []
        for target, order in sorted(orders.items()):
            if isinstance(order, VesselOrder):
                msg, topic, pub = (VesselCommand(engine_order=order.engine, steering_angle=order.helm,
                                                 anchor=order.anchor), T.vessel_topic(target, T.COMMAND),
                                   self.cmd_pubs[target])
            else:
                msg, topic, pub = WinchCommand(**dataclasses.asdict(order)), T.rope_topic(target, T.WINCH), \
                    self.winch_pubs[target]
            msg.header.stamp = stamp
            data = serialize_message(msg)
            if topic in self.order_topics:
                self.own_sent.setdefault(topic, collections.deque(maxlen=256)).append(data)
            pub.publish(data)
            self.owners.sent(target, k)
            ordered.append(target)
            self.event(k, "order", target, self._describe(msg) + (
                " (confirms the held orders after an outside order)" if target in confirm else ""))
        stamp_ns = k * self.period_ns
        # the trigger first: the nodes start computing while /clock goes out (they stamp by
        # step number and do not read the clock to compute)
        self.awaited = k + 1
        ordered = sorted(set(ordered + self.piloted))
        self.send_triggers(k, ordered)
        self._publish(self.step_pub, rc.SIM_STEP_TOPIC, cdr.sim_step_cdr(
            stamp_ns, k, self.period_ns * 1e-9, ordered, self.run_id))
        self._publish(self.clock_pub, "/clock", cdr.clock_cdr(stamp_ns))
        if self.recorder:
            self.recorder.log_time_ns = (k + 1) * self.period_ns

    @staticmethod
    def _describe(order) -> str:
        if isinstance(order, WinchCommand):
            return describe(WINCH, WinchOrder(order.payout_rate, order.mode, order.set_tension,
                                              order.recover_tension, order.brake_load))
        anchor = {0: "", 1: ", let go anchor", 2: ", heave up anchor"}[order.anchor]
        return f"engine {order.engine_order:+.2f}, steering {math.degrees(order.steering_angle):+.1f} deg{anchor}"

    def event(self, k: int, kind: str, target: str, detail: str, value: float = math.nan) -> None:
        ev = ScenarioEvent(step=k, source=self.get_fully_qualified_name(), kind=kind, target=target,
                           detail=detail, value=float(value))
        ev.header.stamp = rc.step_time(k, self.period_ns)
        self.event_pub.publish(ev)


def _takes(msg) -> bool:
    """Would the node take this order (finite values, a known anchor order or winch mode)? The
    conductor counts only those as given."""
    if isinstance(msg, cdr.WinchCommandIn):
        return all(math.isfinite(x) for x in msg[1:]) and msg.mode in (0, 1, 2) and min(msg[3:]) >= 0.0
    return math.isfinite(msg.engine_order) and math.isfinite(msg.steering_angle) and msg.anchor in (0, 1, 2)


def _said(answer: Optional[Tuple[bool, str]]) -> str:
    if answer is None:
        return "nothing"
    return "ok" if answer[0] else f"failed ({answer[1]!r})"


def _node_of(info) -> str:
    ns = info.node_namespace.rstrip("/")
    return f"{ns}/{info.node_name}"


class StopSignals:
    """Ctrl-C (SIGINT) and SIGTERM end a run the same way: the handler only notes the signal; the
    run loop sees it within a millisecond, stops the nodes and the caller finalises the
    recording. (rclpy's own handlers would shut the context down under the running loop.)"""

    def __init__(self):
        self.signum: Optional[int] = None
        self._old = {}

    def __enter__(self):
        import threading
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                old = self._old[sig] = signal.signal(sig, self._note)
                earlier = getattr(old, "__self__", None)
                if isinstance(earlier, StopSignals) and earlier.signum is not None and self.signum is None:
                    self.signum = earlier.signum  # noted by the StopSignals before this one (the runner's start)
        return self

    def _note(self, signum, frame) -> None:
        self.signum = signum

    def check(self) -> None:
        if self.signum is not None:
            raise Interrupted(self.signum)

    def __exit__(self, *exc) -> None:
        for sig, handler in self._old.items():
            signal.signal(sig, handler)


def run(sc: Scenario, scenario_path: str, log_dir: str, *, ready_timeout: float = 240.0,
        stall_timeout: float = 30.0, steps: Optional[int] = None, extra_nodes: Optional[List[Node]] = None,
        on_step: Optional[Callable[[int], None]] = None, recorder=None, layout: str = DEFAULT_LAYOUT,
        on_finished: Optional[Callable[[int], Callable[[], bool]]] = None,
        run_id: Optional[str] = None, external: Sequence[str] = (), groups: Optional[int] = None) -> RunStats:
    """Start the nodes (each its own process, or all in this process on one executor), run the
    scenario, stop everything. Raises RunError naming the node (DomainInUse before anything
    starts if another run is on the domain) and Interrupted on SIGINT / SIGTERM.
    on_finished(final stamp ns), called after the last step while the nodes still run, returns a
    predicate: the run waits (up to 5 s) until it holds, e.g. until a late subscriber got the
    final state.
    external: names of nodes ("/tug/vessel") the runner does not start (resolve_external): started
    by somebody else (other PCs; `-p run_id:=<this run's id>`, or no run_id: such a node joins the
    first run it sees), waited for until they announce themselves (ready_timeout), then stepped,
    watched (stall_timeout) and recorded (by subscription) like the others."""
    if layout not in LAYOUTS:
        raise ValueError(f"layout {layout!r}: expected one of {LAYOUTS}")
    run_id = run_id or new_run_id()
    specs = node_specs(sc, scenario_path, run_id)
    n_steps = sc.steps if steps is None else steps
    unknown = sorted(set(external) - {s.name for s in specs})
    if unknown:
        raise ValueError(f"external node(s) {unknown} are not nodes of the scenario")
    session = _Session(sc, specs, log_dir, recorder, layout, run_id, instrument_specs(sc, scenario_path),
                       external, groups)
    with StopSignals() as session.stop:
        try:
            session.start(extra_nodes or [], ready_timeout)
            session.step(n_steps, stall_timeout, on_step)
            session.settle(on_finished(n_steps * session.conductor.period_ns) if on_finished else (lambda: True))
            session.check_result()
            return session.stats
        finally:
            session.close()


class _Session:
    """One run of run(): the conductor, its executor and the nodes, from start-up to shutdown."""

    def __init__(self, sc: Scenario, specs: List[NodeSpec], log_dir: str, recorder, layout: str, run_id: str,
                 instruments: List[NodeSpec] = (), external: Sequence[str] = (), group_count: Optional[int] = None):
        self.sc, self.specs, self.recorder, self.layout = sc, specs, recorder, layout
        self.external = set(external)
        self.seen_in_graph: set = set()  # external nodes seen in the ROS graph (gone_external)
        self.graph_check = 0.0  # when wait_for looks at the ROS graph next (strangers, external nodes gone)
        self.look_times: Deque[float] = collections.deque(maxlen=8)   # s each of the last graph looks took
        self.own_specs = [s for s in specs if s.name not in self.external]  # the nodes this runner starts
        # the external nodes' per-step outputs, subscribed by the recorder: waited for every step
        self.awaited_outputs = external_outputs(sc, sorted(self.external))[1] if recorder and external else ()
        self.stop: Optional[StopSignals] = None  # set by run() for the time the run handles the signals
        # the nodes in this process (one_process: all; groups: the first group) and in node processes
        if layout == "groups":
            count = group_count or default_group_count(self.own_specs, 1.0 / sc.exchange_rate, cores())
            first, *others = node_groups(self.own_specs, count)
        else:
            first, others = (self.own_specs, []) if layout == "one_process" else ([], [[s] for s in self.own_specs])
        self.in_runner: List[NodeSpec] = first
        self.procs = NodeProcesses([], log_dir, recorder, channels=True, groups=[g for g in others if g])
        # the per-step state topics of every node of the run: topic -> the node that publishes it
        self.state_owners = per_step_outputs(sc, [s.name for s in specs])
        # bridge equipment: own processes in either layout, outside the step protocol
        self.instruments = NodeProcesses(instruments, log_dir)
        self.conductor = Conductor(sc, [s.name for s in specs], recorder, run_id, external=self.external)
        self.executor = rc.make_executor()
        self.executor.add_node(self.conductor)
        self.local_nodes: List[Node] = []
        self.stats = RunStats(run_id=run_id, external=sorted(self.external))

    def start(self, extra_nodes: List[Node], ready_timeout: float) -> None:
        """Check the domain, start the nodes, wait for their ready signal and for every
        subscription the first step needs."""
        conductor, recorder = self.conductor, self.recorder
        conductor.check_domain(self.executor)
        self.stop.check()
        dead = shm_hygiene.remove_dead_fastdds_files()
        if dead:
            conductor.get_logger().info(f"removed {len(dead)} dead Fast DDS shared-memory file(s) of killed "
                                        f"processes from {shm_hygiene.SHM_DIR}")
        if recorder is not None and self.in_runner:
            record_feed.install(recorder.feed_in_process)
        local_channels = {}
        if self.in_runner:  # nodes in this process: a pair of queues each, no descriptor
            pairs = {s.name: step_channel.local_pair() for s in self.in_runner}
            local_channels = {name: pair[0] for name, pair in pairs.items()}
            step_channel.install(lambda name: pairs[name][1] if name in pairs else None)
        try:
            self.local_nodes = in_process_nodes(self.in_runner)
        finally:
            record_feed.install(None)
            step_channel.install(None)
        for node in extra_nodes + ([recorder] if recorder else []) + self.local_nodes:
            self.executor.add_node(node)
        self.procs.start()
        conductor.channels = {**local_channels, **self.procs.channels}
        conductor.wire_only = conductor.expected - set(conductor.channels)
        self.instruments.start()
        self.wait_for(0, ready_timeout, "starting up")
        self._wait_for_matches(ready_timeout)
        # a stranger seen only now (the look before the start is one discovery window) is refused
        # before step 0, so nothing of it can mix into the run
        own = conductor.expected | {n.get_fully_qualified_name() for n in extra_nodes + self.local_nodes
                                    + ([recorder] if recorder else [])}
        conductor.refuse_if_found(self.executor, lambda: conductor.participants_beyond(own)
                                  + conductor.state_intruders(self.state_owners),
                                  " (seen once this run's nodes were up; nothing was stepped)")
        if self.external:
            self.gone_external()  # notes the external nodes in the graph: from now on, leaving it stops the run

    def _wait_for_matches(self, ready_timeout: float) -> None:
        """Triggers and orders are volatile: every participant (and the recorder) must have
        matched them before step 0 goes out."""
        recorder = self.recorder
        want = 2 if recorder else 1
        needs = [(p, want + self.conductor.own_readers(p)) for p in self.conductor.order_publishers()]
        needs.append((self.conductor.step_pub, len(self.specs)))
        deadline = time.monotonic() + ready_timeout
        conductor = self.conductor

        def unrecorded_ready() -> list:
            # the ready answers on the wire, recorded as /sim/step_done of step 0: a node in this
            # process is triggered on its channel the moment step 0 is sent (take_triggers), and
            # then stops repeating the answer its wire copy may not have reached us with yet
            if not recorder:
                return []
            return [n for n in conductor.channels if not conductor.wire_copies.get(n, {}).get(0)]
        while any(p.get_subscription_count() < n for p, n in needs) or (recorder and recorder.unmatched_topics()) \
                or unrecorded_ready():
            self.executor.spin_once(timeout_sec=0.01)
            self.stop.check()
            if time.monotonic() > deadline:
                late = [p.topic_name for p, n in needs if p.get_subscription_count() < n]
                late += recorder.unmatched_topics() if recorder else []
                late += [f"{rc.STEP_DONE_TOPIC} (the ready answer of {n})" for n in unrecorded_ready()]
                raise RunError(f"no subscriber matched topic(s) {late} within {ready_timeout:g} s")

    def step(self, n_steps: int, stall_timeout: float, on_step: Optional[Callable[[int], None]]) -> None:
        """Steps 0 .. n_steps-1, each once every node has answered the one before (realtime:
        and its wall-clock time has come); fills self.stats."""
        sc, conductor, executor, recorder, stats = self.sc, self.conductor, self.executor, self.recorder, self.stats
        conductor.event(0, "scenario_started", "", f"scenario '{sc.name}' (run {stats.run_id}): {n_steps} steps "
                        f"at {sc.exchange_rate:g} Hz, {sc.mode}")
        conductor.announce_manned(0)
        if recorder:
            recorder.flush()   # the start-up's messages (every node's step 0, latched), before the clock starts
        rc.settle_heap()       # the start-up's objects out of the collector's way (and the in-runner nodes')
        t_start = time.monotonic()
        cpu_start = time.process_time() + self.procs.cpu_seconds()
        period = conductor.period_ns * 1e-9
        for k in range(n_steps):
            if sc.mode == "realtime":
                target = t_start + k * period
                now = time.monotonic()
                if k > 0 and now > self.graph_check and target - now > max(
                        GRAPH_CHECK_IDLE, 1.5 * max(self.look_times, default=0.0)):
                    self.look_at_graph(k, f"waiting to start step {k}")   # in the idle time, not in a step
                while time.monotonic() < target:   # asleep until a message comes or the step is due
                    executor.spin_once(timeout_sec=max(0.0, target - time.monotonic()))
                self.stop.check()
                late = time.monotonic() - target
                stats.lateness.append(late)
            t0 = time.monotonic()
            if conductor.watched:
                self.wait_for_states(k, stall_timeout)
            self.deliver_local_inputs(k)
            conductor.send_step(k)
            self.step_local_nodes(f"computing step {k} -> {k + 1}")
            if recorder:
                recorder.flush()  # the previous step's messages, written while the nodes compute
            self.wait_for(k + 1, stall_timeout, f"computing step {k} -> {k + 1}")
            if self.awaited_outputs:
                self.wait_for_outputs(k + 1, stall_timeout)
            stats.round_trips.append(time.monotonic() - t0)
            conductor.done.pop(k, None)
            stats.steps_done = k + 1
            self.stop.check()
            if sc.mode == "realtime" and k == 0:
                # The clock starts when step 0 is done: every node's first step carries one-off work
                # (code run for the first time, first messages on each topic; measured twice a
                # steady step with eight tows in one process), part of starting the run, like the
                # settling. Step 1 is due one period later, and every step after it on time.
                stats.first_step = time.monotonic() - t_start
                t_start = time.monotonic() - period
            over = time.monotonic() - (t_start + (k + 1) * period)
            if sc.mode == "realtime" and k > 0 and over > 0.0:
                stats.overruns += 1
                if len(stats.overrun_steps) < 5:
                    stats.overrun_steps.append((k, over))
            if on_step:
                on_step(k + 1)
        stats.wall_time = time.monotonic() - t_start
        stats.cpu_time = time.process_time() + self.procs.cpu_seconds() - cpu_start
        stats.compute_times = conductor.compute_times
        conductor.event(n_steps, "scenario_finished", "", f"{n_steps} steps in {stats.wall_time:.1f} s wall")

    def wait_for_states(self, k: int, timeout: float) -> None:
        """Spin until the conductor has the odometry of step k of every vessel a pending
        trigger watches (the nodes answer StepDone and publish their state independently)."""
        deadline = time.monotonic() + timeout
        while self.conductor.states_needed(k):
            self.executor.spin_once(timeout_sec=0.001)
            self.stop.check()
            if time.monotonic() > deadline:
                raise RunError(f"no odometry of step {k} from {', '.join(self.conductor.states_needed(k))} within "
                               f"{timeout:g} s: a state-triggered event cannot be evaluated")

    def wait_for_outputs(self, step: int, timeout: float) -> None:
        """Spin until the recorder holds every per-step output of step `step` of the external
        nodes (subscribed; a StepDone may overtake them on the network, and the next steps could
        push a late one out of its publisher's history)."""
        stamp = step * self.conductor.period_ns
        deadline = time.monotonic() + timeout
        while self.recorder.lagging(stamp, self.awaited_outputs):
            self.executor.spin_once(timeout_sec=0.001)
            self.stop.check()
            if time.monotonic() > deadline:
                late = ", ".join(self.recorder.lagging(stamp, self.awaited_outputs))
                raise RunError(f"no message of step {step} on {late} "
                               f"(external node) within {timeout:g} s: it answered the step, its output did not arrive")

    def settle(self, settled: Callable[[], bool]) -> None:
        """Let the last messages reach subscribers in this process (recorder, summary): 0.3 s,
        and up to 5 s until settled() holds."""
        start = time.monotonic()
        while time.monotonic() < start + 0.3 or (not settled() and time.monotonic() < start + 5.0):
            self.executor.spin_once(timeout_sec=0.01)

    def deliver_local_inputs(self, k: int, limit: float = 0.05) -> None:
        """Before step k is sent, the executor hands this process's nodes the inputs of step k it
        still holds (the other nodes' outputs of the step before), so that they step at once on
        the trigger. Paced, the idle time before a step does this; a step that ran late leaves no
        idle time, and the nodes, triggered without their inputs, stepped from the executor's
        callbacks instead, at twice a step's CPU, so that the run stayed late for 10-20 steps
        (eight tows in one process). Bounded: what is still missing after `limit` s is waited for
        as before (wait_for)."""
        if not self.local_nodes or k == 0:
            return
        until = time.monotonic() + limit
        while not all(n.has_state_inputs(k) for n in self.local_nodes) and time.monotonic() < until:
            self.spin_once(f"delivering the inputs of step {k}")

    def step_local_nodes(self, what: str) -> None:
        """The nodes of this process take the trigger just sent (SteppedNode.take_triggers); a
        node's failure is reported by its failed answer, as in wait_for."""
        try:
            for node in self.local_nodes:
                node.take_triggers()
        except Exception as exc:  # noqa: BLE001 - an in-process node failed in its step
            self.node_failed(exc, what)

    def spin_once(self, what: str) -> None:
        """One round of the executor; an in-process node's failure in a callback stops the run."""
        try:
            self.executor.spin_once(timeout_sec=0.001)
        except rclpy.executors.ExternalShutdownException:
            raise  # the context was shut down: the caller finalises the recording
        except Exception as exc:  # noqa: BLE001 - an in-process node failed in its callback
            self.node_failed(exc, what)

    def node_failed(self, exc: Exception, what: str) -> None:
        """An in-process node raised: its failed answer names it, as a node process's does."""
        self.conductor.take_answers()
        if self.conductor.failures:
            self.raise_failure()
        raise RunError(f"a node failed while {what}: {exc!r}") from exc

    def wait_for(self, step: int, timeout: float, what: str) -> None:
        """Spin until every node has answered StepDone(step); RunError if a node failed, died or
        stays silent for timeout s, Interrupted on a stop signal."""
        conductor, procs, recorder = self.conductor, self.procs, self.recorder
        now = time.monotonic()
        deadline = now + timeout
        next_check = now  # processes are polled every 20 ms, not after every message
        rescue_at = now + RESCUE_AFTER
        expected = conductor.expected
        done = conductor.done
        while done.get(step) != expected:
            self.spin_once(what)
            conductor.take_answers()
            if conductor.failures:
                self.raise_failure()
            now = time.monotonic()
            if now < next_check:
                continue
            next_check = now + 0.02
            self.stop.check()
            if now > rescue_at:  # the EventsExecutor may sit on an answer (ros_common.take_missed)
                rescue_at = now + RESCUE_AFTER
                conductor.rescued += rc.take_missed(conductor.done_sub, conductor._on_done_raw)
                for node in self.local_nodes:
                    node.poll()
            if recorder:
                recorder.flush()  # a node blocked on a full feed pipe must never stall the step
            for group, kind in ((procs, "node"), (self.instruments, "instrument")):
                dead = group.dead()
                if dead:
                    raise RunError(f"{kind} {dead} died (exit code {group.procs[dead].returncode}) while {what}; "
                                   f"last lines of its log ({group.logs[dead]}):\n{group.tail(dead)}")
            for when, why in conductor.broken_channels.values():
                if now > when + 1.0:
                    raise RunError(why)
            overdue = GRAPH_CHECK_OVERDUE if self.sc.mode == "realtime" else 0.0
            if step > 0 and now > self.graph_check + overdue:  # kept across steps: a step takes a few ms
                self.look_at_graph(step - 1, what)
            if now > deadline:
                missing = sorted(conductor.expected - conductor.done.get(step, set()))
                remote = [n for n in missing if n in self.external]
                note = (f" ({', '.join(remote)}: external, not started by this runner: is it running, on this "
                        f"ROS_DOMAIN_ID, and can this host reach it?)" if remote else "")
                if step == 0 and remote:
                    raise RunError(f"node(s) {', '.join(missing)} did not announce themselves: no StepDone(0) within "
                                   f"{timeout:g} s while {what}{note}")
                raise RunError(f"node(s) {', '.join(missing)} stopped answering: no StepDone({step}) within "
                               f"{timeout:g} s while {what}{note}")

    def raise_failure(self) -> None:
        """The first failure a node reported (or the runner found), as Untrusted if it is a
        conflict: two different messages for one step."""
        text = self.conductor.failures[0]
        if CONFLICT_MARK in text:
            raise Untrusted(f"{text}; the run cannot be trusted")
        raise RunError(text)

    def look_at_graph(self, k: int, what: str) -> None:
        """The periodic look at the ROS graph: strangers on the run's topics, external nodes gone."""
        began = time.monotonic()
        self.graph_check = began + GRAPH_CHECK_PERIOD
        self.look_for_strangers(k)
        gone = self.gone_external() if self.external else []
        self.look_times.append(time.monotonic() - began)
        if gone:
            raise RunError(f"node(s) {', '.join(gone)} left the network while {what}: external, their DDS "
                           "participant is no longer announced (process ended, or its host is down or cut off)")

    def look_for_strangers(self, k: int) -> None:
        """Untrusted if a stranger publishes one of the run's per-step state topics; strangers on
        the protocol topics are named (their messages are refused)."""
        found = self.conductor.state_intruders(self.state_owners)
        if found:
            raise Untrusted(f"a stranger publishes the run's state (seen at step {k}): {'; '.join(found)}; the run "
                            "cannot be trusted")
        self.conductor.note_protocol_strangers(k)

    def check_result(self) -> None:
        """After the last step: no late failure or intrusion, and the step count the summary will
        state is what every node published: each node's last answer on its channel, and with a
        recording every per-step output topic's count (step 0 and each step run). Untrusted
        naming the node otherwise."""
        conductor, recorder, steps = self.conductor, self.recorder, self.stats.steps_done
        conductor.take_answers()
        if conductor.failures:
            self.raise_failure()
        self.look_for_strangers(steps)
        self.stats.strangers = dict(conductor.strangers)
        short = [f"{n} answered step {conductor.last_answer.get(n, 0)}" for n in sorted(conductor.channels)
                 if conductor.last_answer.get(n, 0) != steps]
        if recorder:
            recorder.flush()
            for topic, owner in sorted(self.state_owners.items()):
                n = recorder.counts.get(topic, 0)
                # fed by the node: exactly one a step; subscribed (external): a repeat may be recorded
                if n != steps + 1 and not (owner in self.external and n > steps):
                    short.append(f"{owner} published {n} message(s) on {topic}, expected {steps + 1} (steps 0-{steps})")
                else:
                    self.stats.outputs_checked += 1
        if short:
            raise Untrusted(f"{steps} steps were counted, but {'; '.join(short)}: the run cannot be trusted")

    def gone_external(self) -> List[str]:
        """External nodes no longer in the ROS graph: their participant stopped announcing itself
        for its lease duration (Fast DDS default 20 s; 3 s with scripts/fastdds_lan.xml)."""
        present = {f"{ns.rstrip('/')}/{name}" for name, ns in self.conductor.get_node_names_and_namespaces()}
        self.seen_in_graph |= self.external & present
        return sorted(self.seen_in_graph - present)  # one not seen yet is left to the stall timeout

    def close(self) -> None:
        """Protocol counts into the stats, then stop the nodes and the executor."""
        self.stats.refused = dict(self.conductor.refused)
        self.stats.strangers = dict(self.conductor.strangers)
        events = self.sc.events
        self.stats.never_fired = [f"events[{i}] (when {events[i].when.describe()})" for i in self.conductor.triggered
                                  if i not in self.conductor.fired]
        self.stats.node_refused = dict(self.conductor.node_refused)
        self.stats.rescued = self.conductor.rescued
        self.stats.late_wire_copies = self.conductor.late_wire_copies
        self.procs.stop()
        self.instruments.stop()
        self.executor.shutdown()
        for node in self.local_nodes:
            node.destroy_node()
        self.conductor.destroy_node()


def percentile(values: List[float], q: float) -> float:
    return float(np.percentile(np.asarray(values), q)) if values else float("nan")


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use run_scenario")
