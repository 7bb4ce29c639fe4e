"""A stranger on the domain knows what the wire tells it: the run id (from /sim/step), the node
names (from /sim/step_done), the topics (from the graph). Whatever it publishes, a run ends with
the result of an undisturbed run, or stops with a non-zero exit naming the intrusion; never exit
0 with a different result (issue 30, item 1). Before, forged StepDones made a run end "exit 0,
N steps" with its nodes stopped early, a forged ok=false stopped it with the stranger's text,
and a republished towline wrench moved the barge sideways.

The end-to-end attacks run against the real runner and nodes; the bookkeeping (channel against
wire, a state input twice for one step) is checked in-process too, without DDS timing."""
import subprocess
import threading
import time

import numpy as np
import pytest

from conftest import reserved_domain
from test_protocol_hardening import _wait_until_stepping, runner
from test_recording import physics

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

DURATION = 20.0  # 1000 steps, several seconds of stepping: the stranger joins and acts well before the end
STRANGER = "intruder"


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    """The undisturbed run's decoded states."""
    path = tmp_path_factory.mktemp("clean") / "clean.mcap"
    with reserved_domain():
        proc = subprocess.run(runner(path, duration=DURATION), capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return physics(path)


class Stranger:
    """A node of its own, spinning in a thread, that learns the run from the wire and acts on it
    through the callbacks given (each returns how many messages it sent)."""

    def __init__(self, context, on_step=None, on_done=None):
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from tug_msgs.msg import SimStep, StepDone
        from sim_plumbing import ros_common as rc
        self.rc, self.SimStep, self.StepDone = rc, SimStep, StepDone
        self.node = Node(STRANGER, context=context)
        self.run_id = None
        self.names = set()  # the run's node names, as their StepDones tell them
        self.sent = 0
        self._on_step, self._on_done = on_step, on_done
        self.node.create_subscription(SimStep, rc.SIM_STEP_TOPIC, self._step, rc.PROTOCOL_QOS)
        self.node.create_subscription(StepDone, rc.STEP_DONE_TOPIC, self._done, rc.PROTOCOL_QOS)
        self.step_pub = self.node.create_publisher(SimStep, rc.SIM_STEP_TOPIC, rc.PROTOCOL_QOS)
        self.done_pub = self.node.create_publisher(StepDone, rc.STEP_DONE_TOPIC, rc.PROTOCOL_QOS)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)

    def start(self):
        self._thread.start()
        return self

    def _spin(self):
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.01)

    def _step(self, msg):
        self.run_id = msg.run_id
        if self._on_step and self.names:
            self.sent += self._on_step(self, msg)

    def _done(self, msg):
        if msg.run_id:
            self.run_id = self.run_id or msg.run_id
            self.names.add(msg.node)
        if self._on_done and self.run_id:
            self.sent += self._on_done(self, msg)

    def answer(self, node, step, ok=True, error=""):
        self.done_pub.publish(self.StepDone(run_id=self.run_id, node=node, step=step, ok=ok, error=error,
                                            compute_time=0.0001))

    def trigger(self, step, ordered=()):
        msg = self.SimStep(run_id=self.run_id, step=step, period=0.02, ordered=list(ordered))
        msg.header.stamp = msg.time = self.rc.step_time(step, 20_000_000)
        self.step_pub.publish(msg)

    def stop(self):
        self._stop.set()
        self._thread.join(5)
        self.executor.shutdown()
        self.node.destroy_node()  # left on the domain it would be refused by later runs


def attacked_run(tmp_path, ros_domain, rclpy_context, make_stranger, *extra):
    """The tow run with the stranger joining once it steps (before, the runner rightly refuses
    the domain): (exit status, stdout, stderr, recording, messages the stranger sent)."""
    out = tmp_path / "attacked.mcap"
    proc = subprocess.Popen(runner(out, *extra, duration=DURATION), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    stranger = None
    try:
        _wait_until_stepping(ros_domain, tmp_path / "attacked_logs")
        stranger = make_stranger(rclpy_context).start()
        stdout, stderr = proc.communicate(timeout=240)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
        if stranger is not None:
            stranger.stop()
    return proc.returncode, stdout, stderr, out, stranger.sent


def assert_unchanged_or_named(clean, status, stdout, stderr, out):
    """The acceptance rule: exit 0 with the undisturbed result, or a non-zero exit that names
    the stranger."""
    if status == 0:
        got = physics(out)
        for key in clean:
            np.testing.assert_array_equal(clean[key], got[key], err_msg=f"{key}: exit 0 with another result")
        assert f"/{STRANGER}" in stdout, stdout  # and it is named in the summary
    else:
        assert f"/{STRANGER}" in stderr, f"exit {status} without naming the stranger:\n{stdout}\n{stderr}"


def test_forged_answers_for_every_node_change_nothing(clean, tmp_path, ros_domain, rclpy_context):
    """At every SimStep(k) the stranger answers StepDone(k+1) "ok" for every node it has seen
    (the probe's attack: the run ended 'exit 0, 3000 steps' with the nodes stopped at 107)."""
    def on_step(s, msg):
        for name in sorted(s.names):
            s.answer(name, msg.step + 1)
        return len(s.names)
    status, stdout, stderr, out, sent = attacked_run(tmp_path, ros_domain, rclpy_context,
                                                     lambda ctx: Stranger(ctx, on_step=on_step))
    assert sent > 100, (sent, stdout, stderr)
    assert_unchanged_or_named(clean, status, stdout, stderr, out)
    if status == 0:
        assert "StepDone (not the node's)" in stdout, stdout  # refused and counted


def test_a_forged_failure_does_not_stop_the_run(clean, tmp_path, ros_domain, rclpy_context):
    """A StepDone ok=false in a node's name, with the stranger's text, at every step."""
    def on_step(s, msg):
        s.answer(sorted(s.names)[0], msg.step + 1, ok=False, error="engine room fire (forged)")
        return 1
    status, stdout, stderr, out, sent = attacked_run(tmp_path, ros_domain, rclpy_context,
                                                     lambda ctx: Stranger(ctx, on_step=on_step))
    assert sent > 100, (sent, stdout, stderr)
    assert_unchanged_or_named(clean, status, stdout, stderr, out)
    assert "failed at step" not in stderr, stderr  # its text is no node's failure


def test_forged_triggers_ahead_of_the_runner_change_nothing(clean, tmp_path, ros_domain, rclpy_context):
    """As soon as a node answers step k the stranger sends it SimStep(k), ahead of the runner,
    announcing no order (before: the node stepped on it and refused the runner's, a stall)."""
    def on_done(s, msg):
        if msg.run_id != s.run_id or msg.step == 0:
            return 0
        s.trigger(msg.step)
        return 1
    status, stdout, stderr, out, sent = attacked_run(tmp_path, ros_domain, rclpy_context,
                                                     lambda ctx: Stranger(ctx, on_done=on_done),
                                                     "--stall-timeout", "10")
    assert sent > 100, (sent, stdout, stderr)
    assert_unchanged_or_named(clean, status, stdout, stderr, out)


def test_an_injected_towline_wrench_stops_the_run_naming_the_stranger(clean, tmp_path, ros_domain,
                                                                      rclpy_context):
    """The stranger finds the barge's towline wrench topic in the graph and republishes every
    message three times with 5e5 N more to the north (before: the barge went 41.8 m sideways)."""
    from geometry_msgs.msg import WrenchStamped

    def make(ctx):
        s = Stranger(ctx)
        deadline = time.monotonic() + 20
        topics = []
        while not topics and time.monotonic() < deadline:  # the graph is read without spinning
            topics = [t for t, _ in s.node.get_topic_names_and_types() if t.endswith("end_b/wrench")]
            time.sleep(0.05)
        assert topics, s.node.get_topic_names_and_types()
        pub = s.node.create_publisher(WrenchStamped, topics[0], s.rc.LATCHED_STATE_QOS)

        def inject(msg):
            if msg.wrench.force.y > 1e5:
                return  # its own (it reads the topic it writes)
            msg.wrench.force.y += 5e5
            for _ in range(3):
                pub.publish(msg)
            s.sent += 3
        s.node.create_subscription(WrenchStamped, topics[0], inject, s.rc.LATCHED_STATE_QOS)
        return s
    status, stdout, stderr, out, sent = attacked_run(tmp_path, ros_domain, rclpy_context, make)
    # The runner may see the stranger's publisher in the graph and stop before its first copy
    # goes out (seen in ci11); an exit 0 must have come through an attack that was made.
    assert sent > 0 or status != 0, (stdout, stderr)
    assert_unchanged_or_named(clean, status, stdout, stderr, out)
    if status != 0:
        assert status == 5 and "end_b/wrench" in stderr, stderr  # untrusted, naming the topic


# -- the bookkeeping, in-process -----------------------------------------------------------------

def _conductor(rclpy_context, external=()):
    from scenario_runner.conductor import Conductor
    from scenario_format.scenario import load_scenario
    from scenario_format.particulars import scenario_path
    sc = load_scenario(scenario_path("seed000_straight_tow_5kn.yaml"))
    return Conductor(sc, ["/tug/vessel", "/towline/rope"], run_id="r1", external=external, context=rclpy_context)


def test_the_runner_counts_only_the_channel_of_a_node_it_started(rclpy_context):
    """A node with a channel: its answer on the wire counts for nothing; one the channel did not
    say (ok or failed), or a second copy of one it said, is refused and counted; the channel's
    failure stops the run."""
    from sim_plumbing import step_channel
    from sim_plumbing.cdr import DoneIn
    c = _conductor(rclpy_context)
    try:
        tug, tug_node_end = step_channel.local_pair()
        c.channels = {"/tug/vessel": tug}

        def wire(node, step, ok=True, error=""):
            c._on_done(DoneIn(0, "r1", node, step, 0.001, ok, 0, error))
        tug_node_end.send_answer(step_channel.Answer(0, 0.0, True, 0, ""))
        wire("/towline/rope", 0)
        c.take_answers()
        assert c.done[0] == {"/tug/vessel", "/towline/rope"}
        c.awaited = 1
        wire("/tug/vessel", 1)                                   # forged: the channel said nothing
        wire("/tug/vessel", 1, ok=False, error="forged failure")
        assert 1 not in c.done and not c.failures
        assert c.refused["not the node's"] == 2
        tug_node_end.send_answer(step_channel.Answer(1, 0.001, True, 2, ""))
        wire("/tug/vessel", 1)                                   # the node's own copy: agrees, not counted twice
        assert c.done[1] == {"/tug/vessel"} and c.refused["not the node's"] == 2 and not c.refused["duplicate"]
        assert c.node_refused["/tug/vessel"] == 2
        wire("/tug/vessel", 1)                                   # a copy of what the channel said: a second one
        assert c.refused["not the node's"] == 3 and c.done[1] == {"/tug/vessel"}
        tug_node_end.send_answer(step_channel.Answer(1, 0.0, False, 2, "conflicting messages: x"))
        c.take_answers()
        assert c.failures == ["/tug/vessel failed at step 1: conflicting messages: x"]
    finally:
        c.destroy_node()


def test_a_second_answer_in_an_external_nodes_name_stops_the_run(rclpy_context):
    """An external node has only the wire: each step it answers once, so a second StepDone for
    a step it answered is somebody else's in its name, and which one the run went on cannot be
    told: a failure marked as a conflict (the runner stops, untrusted)."""
    from sim_plumbing.cdr import DoneIn
    from sim_plumbing.stepping import CONFLICT_MARK
    c = _conductor(rclpy_context, external=["/tug/vessel"])
    try:
        c.awaited = 1
        c._on_done(DoneIn(0, "r1", "/tug/vessel", 1, 0.001, True, 0, ""))
        assert c.done[1] == {"/tug/vessel"} and not c.failures
        c._on_done(DoneIn(0, "r1", "/tug/vessel", 1, 0.001, True, 0, ""))
        assert len(c.failures) == 1 and CONFLICT_MARK in c.failures[0] and "/tug/vessel" in c.failures[0]
    finally:
        c.destroy_node()


def _wrench(node, step, force_y):
    """A towline wrench on the tug's hull stamped `step`, serialized as the wire carries it."""
    from geometry_msgs.msg import WrenchStamped
    from rclpy.serialization import serialize_message
    from sim_plumbing import ros_common as rc
    msg = WrenchStamped()
    msg.header.frame_id = "tug/base_link"
    msg.header.stamp = rc.step_time(step, node.period_ns)
    msg.wrench.force.y = force_y
    return serialize_message(msg)


def _with_other_padding(data, frame_id_length):
    """`data`, a serialized stamped message whose frame id is followed by doubles, with the padding
    bytes between them set to other values (encapsulation 4 + stamp 8 + length 4 + id + NUL)."""
    end = 4 + 8 + 4 + frame_id_length + 1
    start = end
    while (end - 4) % 8:
        end += 1
    assert end > start, "this frame id leaves no padding"
    return data[:start] + bytes((~b) & 0xFF for b in data[start:end]) + data[end:]


@pytest.mark.parametrize("when", ["before the step", "after the step"])
def test_a_state_input_twice_for_a_step_with_other_content_is_refused_not_applied(rclpy_context, when):
    """The vessel node gets its towline wrench for step 0, then another one stamped 0 with 5e5 N
    more: before the step, the step is not computed on either; after it, the step's result is
    flagged. Either way the node stops stepping and says why (the publishers named); an
    identical copy changes nothing."""
    from rclpy.parameter import Parameter
    from sim_plumbing.cdr import TriggerIn
    from sim_plumbing.stepping import CONFLICT_MARK
    from tug_dynamics.vessel_node import VesselNode
    node = VesselNode(context=rclpy_context, namespace="/tug", parameter_overrides=[
        Parameter("ship_file", value="harbour_tug.yaml"), Parameter("lockstep", value=True),
        Parameter("run_id", value="r"), Parameter("wrench_topics", value=["/towline/end_a/wrench"])])
    try:
        spec = next(s for s in node.inputs if s.topic == "/towline/end_a/wrench")
        node._on_raw_input(spec, _wrench(node, 0, 1000.0))
        node._on_raw_input(spec, _wrench(node, 0, 1000.0))  # a copy: nothing
        assert node.untrusted is None
        # the same message serialized elsewhere: CDR's alignment padding (after the 13-character
        # frame id, before the doubles) is not zeroed by the serializer, so its bytes may differ
        node._on_raw_input(spec, _with_other_padding(_wrench(node, 0, 1000.0), len("tug/base_link")))
        assert node.untrusted is None
        if when == "after the step":
            node._on_trigger(TriggerIn(0, "r", 0, ()))
            assert node.step_index == 1
        node._on_raw_input(spec, _wrench(node, 0, 1000.0 + 5e5))
        if when == "before the step":
            node._on_trigger(TriggerIn(0, "r", 0, ()))
        assert node.untrusted is not None and node.untrusted.startswith(CONFLICT_MARK), node.untrusted
        assert "/towline/end_a/wrench" in node.untrusted and "step 0" in node.untrusted
        assert node.step_index == (0 if when == "before the step" else 1)  # nothing computed on it
        node._on_raw_input(spec, _wrench(node, 1, 1000.0))
        node._on_trigger(TriggerIn(node.period_ns, "r", 1, ()))
        assert node.step_index <= 1  # and it steps no further
        assert node.complaints.counts["conflict"] == 1
    finally:
        node.destroy_node()


def _vessel(rclpy_context, channel=None):
    """A lockstep tug of run "r" with no inputs but its orders; `channel`: the node's end of a
    local channel, as the runner of --layout one_process hands it over."""
    from rclpy.parameter import Parameter
    from sim_plumbing import step_channel
    from tug_dynamics.vessel_node import VesselNode
    step_channel.install((lambda name: channel if name == "/tug/vessel" else None) if channel else None)
    try:
        return VesselNode(context=rclpy_context, namespace="/tug", parameter_overrides=[
            Parameter("ship_file", value="harbour_tug.yaml"), Parameter("lockstep", value=True),
            Parameter("run_id", value="r")])
    finally:
        step_channel.install(None)


def test_a_node_with_a_channel_steps_only_on_the_runners_triggers(rclpy_context):
    """A SimStep on the wire that the channel did not send (right run id, right step) is refused
    and counted; the runner's own (channel first, then the wire's copy) steps the node once, and
    its answer goes to the channel."""
    from sim_plumbing import cdr, step_channel
    runner_end, node_end = step_channel.local_pair()
    node = _vessel(rclpy_context, node_end)
    try:
        assert node.channel is node_end
        node._on_trigger_raw(cdr.sim_step_cdr(0, 0, 0.02, [], "r"))      # a stranger's, with the run id
        assert node.step_index == 0 and node.complaints.counts["unconfirmed trigger"] == 1
        runner_end.send_trigger(0, [])
        node._on_trigger_raw(cdr.sim_step_cdr(0, 0, 0.02, [], "r"))      # the runner's copy on the wire
        assert node.step_index == 1 and node.complaints.counts["unconfirmed trigger"] == 1
        answers = runner_end.answers()
        assert answers[-1].step == 1 and answers[-1].ok and answers[-1].refused == 1
    finally:
        node.destroy_node()


def test_a_wire_trigger_far_behind_the_channel_is_late_not_a_strangers(rclpy_context):
    """The wire's SimStep copies lag the channel when the executor falls behind a fast run: one more
    than MAX_LEAD_STEPS behind the channel's latest trigger cannot be checked and is counted as late,
    not refused as a stranger's; within the window one the channel did not send is refused as ever."""
    from sim_plumbing import cdr, step_channel
    from sim_plumbing.stepping import MAX_LEAD_STEPS
    runner_end, node_end = step_channel.local_pair()
    node = _vessel(rclpy_context, node_end)
    try:
        for k in range(MAX_LEAD_STEPS + 30):
            runner_end.send_trigger(k, [])
            node.take_triggers()
        assert node.step_index == MAX_LEAD_STEPS + 30
        node._on_trigger_raw(cdr.sim_step_cdr(5 * 20_000_000, 5, 0.02, [], "r"))
        assert node.late_wire_triggers == 1 and node.complaints.counts["unconfirmed trigger"] == 0
        node._on_trigger_raw(cdr.sim_step_cdr(120 * 20_000_000, 120, 0.02, ["tug"], "r"))   # not as sent
        assert node.late_wire_triggers == 1 and node.complaints.counts["unconfirmed trigger"] == 1
    finally:
        node.destroy_node()


def test_a_node_without_a_channel_stops_on_two_different_triggers_for_a_step(rclpy_context):
    """Started by somebody else, a node has the wire only: a second SimStep for a step with
    another `ordered` means a stranger's trigger may have been used; it stops stepping."""
    from sim_plumbing.cdr import TriggerIn
    from sim_plumbing.stepping import CONFLICT_MARK
    node = _vessel(rclpy_context)
    try:
        assert node.channel is None
        node._on_trigger(TriggerIn(0, "r", 0, ()))          # the stranger's, first: no order announced
        assert node.step_index == 1
        node._on_trigger(TriggerIn(0, "r", 0, ()))          # an identical copy: refused, nothing more
        assert node.untrusted is None
        node._on_trigger(TriggerIn(0, "r", 0, ("tug",)))    # the runner's: it announced an order
        assert node.untrusted is not None and node.untrusted.startswith(CONFLICT_MARK)
        assert "/sim/step" in node.untrusted and "SimStep(0)" in node.untrusted
        node._on_trigger(TriggerIn(node.period_ns, "r", 1, ()))
        assert node.step_index == 1  # it steps no further
    finally:
        node.destroy_node()
