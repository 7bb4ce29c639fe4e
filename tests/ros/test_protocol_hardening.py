"""A lockstep that trusts no stranger (run identity, refused and counted
stray, duplicate and untriggered messages, one run per domain), no orphans whatever kills the
runner, SIGTERM like Ctrl-C, orders that cannot stall or grow a node."""
import os
import re
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

from conftest import DOMAIN_CHECK_WAIT_VARIABLE, executable_path, processes_of_domain, spin_until
from test_recording import physics, _node_pid

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

SCENARIO = "seed000_straight_tow_5kn.yaml"
DURATION = 4.0


def _long_scenario():
    """The tow scenario lasting an hour (its own duration caps --duration)."""
    import tempfile
    import yaml
    from scenario_format.particulars import scenario_path
    sc = dict(yaml.safe_load(open(scenario_path(SCENARIO))), duration=3600.0)
    path = os.path.join(tempfile.mkdtemp(prefix="tugsim-long-"), "long_tow.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(sc, f)
    return path


def runner(out, *extra, duration=DURATION):
    scenario = SCENARIO if duration <= 120 else _long_scenario()
    # every node its own process: these tests kill, read and disturb the node processes
    args = [executable_path("scenario_runner", "run_scenario"), scenario, "--duration", str(duration), "--quiet",
            "--layout", "processes"]
    args += ["--output", str(out)] if out else ["--no-record", "--log-dir", "/tmp/tugsim-test-logs"]
    return args + list(extra)


def _domain_nodes(domain):
    """pids of simulator node processes of this domain."""
    return [p for p in (_node_pid(pat, domain) for pat in ("__ns:=/tug", "__ns:=/barge", "__ns:=/towline")) if p]


def _wait_until_stepping(domain, log_dir, timeout=120):
    """Until the run's /clock is past step 0 (its start-up checks are behind it)."""
    import rclpy
    from rclpy.node import Node
    from rosgraph_msgs.msg import Clock
    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=domain)
    node = Node("stepping_watch", context=ctx)
    try:
        seen = []
        node.create_subscription(Clock, "/clock", lambda m: seen.append(m.clock.sec * 10**9 + m.clock.nanosec), 10)
        assert spin_until(node, lambda: any(t > 0 for t in seen), timeout), f"no step past 0 (logs: {log_dir})"
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=ctx)


@pytest.mark.timeout(600)  # two 120 s runs, one under a flood: about 150 s idle, over 300 s on saturated cores (ci22)
def test_stray_triggers_and_answers_change_nothing(tmp_path, ros_domain, rclpy_context):
    """A stranger floods /sim/step and /sim/step_done (other run ids, no run id, every step
    number): the trajectories are those of an undisturbed run, and the refusals are counted."""
    from rclpy.node import Node
    from tug_msgs.msg import SimStep, StepDone
    from sim_plumbing import ros_common as rc
    clean = tmp_path / "clean.mcap"
    # the undisturbed run in one process (the same physics, a third of the CPU); the disturbed one
    # below, long enough (about 7 s of wall time) for the stranger to be discovered while it steps,
    # in the process layout the stranger's messages reach
    assert subprocess.run(runner(clean, "--layout", "one_process", duration=120), capture_output=True, text=True,
                          timeout=240).returncode == 0
    stop = threading.Event()
    sent = [0]
    disturbed = tmp_path / "disturbed.mcap"
    log_dir = tmp_path / "disturbed_logs"
    proc = subprocess.Popen(runner(disturbed, duration=120), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    # the stranger appears once the run is under way (before, the runner rightly refuses the domain)
    _wait_until_stepping(ros_domain, log_dir)
    node = Node("stranger", context=rclpy_context)
    step_pub = node.create_publisher(SimStep, rc.SIM_STEP_TOPIC, rc.PROTOCOL_QOS)
    done_pub = node.create_publisher(StepDone, rc.STEP_DONE_TOPIC, rc.PROTOCOL_QOS)

    def flood():
        rng = np.random.default_rng(1)
        while not stop.is_set():
            k = int(rng.integers(0, 3000))
            step_pub.publish(SimStep(run_id=["", "other-run"][k % 2], step=k, period=0.02, ordered=["tug"]))
            for name in ("/tug/vessel", "/barge/vessel", "/towline/rope", "/ghost/vessel"):
                done_pub.publish(StepDone(run_id="other-run", node=name, step=k, ok=True))
            sent[0] += 5
            time.sleep(0.002)

    thread = threading.Thread(target=flood, daemon=True)
    thread.start()
    try:
        stdout, stderr = proc.communicate(timeout=420)
    finally:
        stop.set()
        thread.join(5)
        node.destroy_node()  # a stranger left on the domain would be refused by later runs
    assert proc.returncode == 0, stdout + stderr
    assert sent[0] > 100
    assert "refused protocol messages" in stdout, stdout  # counted, and said
    assert "another run" in stdout
    a, b = physics(clean), physics(disturbed)
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_runner_refuses_answers_not_of_this_run_step_or_node(rclpy_context):
    """The runner's bookkeeping without DDS timing: only an answer of this run, from a node of
    the run, for the step now due, once, counts."""
    from scenario_runner.conductor import Conductor
    from scenario_format.scenario import load_scenario
    from scenario_format.particulars import scenario_path
    from sim_plumbing.cdr import DoneIn
    sc = load_scenario(scenario_path(SCENARIO))
    c = Conductor(sc, ["/tug/vessel", "/towline/rope"], run_id="r1", context=rclpy_context)
    try:
        def done(node, step, run="r1", ok=True):
            c._on_done(DoneIn(0, run, node, step, 0.001, ok, 0, "" if ok else "boom"))
        for _ in range(3):
            done("/tug/vessel", 0)  # the ready signal repeats: not an anomaly
        done("/towline/rope", 0)
        assert c.done[0] == {"/tug/vessel", "/towline/rope"} and not c.refused
        c.awaited = 1  # SimStep(0) went out
        done("/tug/vessel", 1, run="r0")          # another run
        done("/ghost/vessel", 1)                   # not in the run
        done("/tug/vessel", 7)                     # a step that was not triggered
        done("/tug/vessel", 1)
        done("/tug/vessel", 1)                     # duplicate
        assert c.done[1] == {"/tug/vessel"}
        assert dict(c.refused) == {"another run": 1, "not in the run": 1, "step not triggered": 1, "duplicate": 1}
        done("/towline/rope", 1)
        assert c.done[1] == {"/tug/vessel", "/towline/rope"}
    finally:
        c.destroy_node()


def test_wire_copies_far_behind_the_channel_are_late_not_strangers(rclpy_context):
    """A node with a channel: its StepDone on the wire is checked against what its channel said, for
    the last ANSWERS_KEPT steps. In a fast run the executor falls behind and the wire's copies come
    late (seen: 900 steps behind at 1000 steps/s, a ship and a bank): a copy older than that is
    counted as late, not refused as somebody else's answer; within the window a copy the channel
    did not say is refused as before."""
    from scenario_runner.conductor import ANSWERS_KEPT, Conductor
    from scenario_format.scenario import load_scenario
    from scenario_format.particulars import scenario_path
    from sim_plumbing import step_channel
    from sim_plumbing.cdr import DoneIn
    sc = load_scenario(scenario_path(SCENARIO))
    c = Conductor(sc, ["/tug/vessel", "/towline/rope"], run_id="r1", context=rclpy_context)
    try:
        runner_end, node_end = step_channel.local_pair()
        c.channels["/tug/vessel"] = runner_end
        for k in range(1, 201):
            c.awaited = k
            node_end.send_answer(step_channel.Answer(k, 0.001, True, 0, ""))
            c.take_answers()

        def wire(step, ok=True):
            c._on_done(DoneIn(0, "r1", "/tug/vessel", step, 0.001, ok, 0, "" if ok else "boom"))
        wire(200 - ANSWERS_KEPT - 1)
        wire(10)
        assert c.late_wire_copies == 2 and not c.refused
        wire(200 - ANSWERS_KEPT)                 # the oldest kept: the channel's own answer, a copy
        wire(150, ok=False)                      # within the window, not what the channel said
        assert c.late_wire_copies == 2 and dict(c.refused) == {"not the node's": 1}
    finally:
        c.destroy_node()


def test_second_run_on_a_domain_is_refused_and_sigkill_leaves_no_orphans(tmp_path, ros_domain, full_domain_check):
    log_dir = tmp_path / "logs"
    first = subprocess.Popen(runner(None, "--log-dir", str(log_dir), duration=600), stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        _wait_until_stepping(ros_domain, log_dir)
        assert len(_domain_nodes(ros_domain)) == 3
        t0 = time.monotonic()
        second = subprocess.run(runner(None, "--log-dir", str(tmp_path / "logs2")), capture_output=True, text=True,
                                timeout=120)
        assert second.returncode == 4, second.stdout + second.stderr
        assert f"ROS_DOMAIN_ID={ros_domain} is in use by another run" in second.stderr, second.stderr
        # it names the participants discovered in the check's window: at least one of the run's
        assert any(n in second.stderr for n in ("/towline/rope", "/tug/vessel", "/barge/vessel",
                                                "scenario runner /scenario_runner")), second.stderr
        assert time.monotonic() - t0 < 60  # refused at start-up, not after the 240 s start-up timeout
        assert not (tmp_path / "logs2").exists()  # nothing was started
    finally:
        first.send_signal(signal.SIGKILL)
        first.communicate(timeout=30)
    deadline = time.monotonic() + 10
    while _domain_nodes(ros_domain) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert _domain_nodes(ros_domain) == []  # the nodes died with their runner


def test_a_second_run_given_the_same_output_leaves_the_first_recording_whole(tmp_path, ros_domain, run_in_process):
    """Run A records to a.mcap; run B given the same --output (here: on the same domain, as two
    ./run.sh in one clone) is refused before it touches the file, naming A's pid; A ends as it
    would have alone, and its recording holds every step (read back)."""
    from mcap.reader import make_reader
    out = tmp_path / "a.mcap"
    first = subprocess.Popen(runner(out, "--log-dir", str(tmp_path / "logs_a"), duration=30), stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        _wait_until_stepping(ros_domain, tmp_path / "logs_a")
        second = run_in_process("run_scenario", SCENARIO, "--duration", "5", "--quiet", "--output", out,
                                "--log-dir", tmp_path / "logs_b")
        assert second.returncode == 2, second.stderr
        assert f"{out} is being written by another run (pid {first.pid})" in second.stderr, second.stderr
        stdout, stderr = first.communicate(timeout=240)
    finally:
        if first.poll() is None:
            first.kill()
    assert first.returncode == 0, stderr
    said = int(re.search(r"recording: .*a\.mcap \((\d+) messages", stdout).group(1))
    with open(out, "rb") as f:  # read by the mcap library, from its messages
        clock = [m.log_time for _, ch, m in make_reader(f).iter_messages() if ch.topic == "/clock"]
        f.seek(0)
        assert sum(1 for _ in make_reader(f).iter_messages()) == said
    assert len(clock) == 30 * 50 and clock == sorted(clock)  # 30 s at 50 Hz: every step of A
    assert not (tmp_path / "logs_b").exists() and not (tmp_path / ".a.mcap.lock").exists()


@pytest.mark.parametrize("victims", ["runner", "all"])
def test_a_run_after_a_killed_run_on_the_same_domain(tmp_path, ros_domain, victims, full_domain_check):
    """The runner killed with SIGKILL (its nodes then end on their own), or runner and nodes
    killed at once (a container stopped, the OOM killer): the next run on that domain runs to
    its end. (Ports of Fast DDS's shared-memory transport that a killed process still held stay
    in /dev/shm; reused by the next run's participants they lost its messages: a stall.)"""
    log_dir = tmp_path / "killed_logs"
    first = subprocess.Popen(runner(None, "--log-dir", str(log_dir), duration=600), stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
    _wait_until_stepping(ros_domain, log_dir)
    for pid in processes_of_domain(ros_domain) if victims == "all" else [first.pid]:
        os.kill(pid, signal.SIGKILL)
    first.wait(timeout=30)
    deadline = time.monotonic() + 10
    while processes_of_domain(ros_domain) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not processes_of_domain(ros_domain)
    # and a dead data-sharing segment as such a kill leaves it (no process maps it)
    planted = [f"/dev/shm/fastrtps_0000{ros_domain:04d}deadbeef{suffix}" for suffix in ("", "_el")]
    for path in planted:
        with open(path, "wb") as f:
            f.write(b"\0" * 4096)
    time.sleep(1.5)
    t0 = time.monotonic()
    again = subprocess.run(runner(tmp_path / "again.mcap", duration=10), capture_output=True, text=True, timeout=200)
    assert again.returncode == 0, again.stdout + again.stderr
    assert time.monotonic() - t0 < 60  # no stall (30 s each) on the way
    assert not any(os.path.exists(p) for p in planted)


@pytest.mark.parametrize("check_wait", ["default", "0"])
def test_leftover_lockstep_node_is_refused_by_the_next_run(tmp_path, ros_domain, start_node, monkeypatch,
                                                           check_wait):
    """A lockstep node on the domain that is not this run's (left by a killed runner, or started
    by hand) would mix its latched outputs into the run: the runner refuses to start, naming it.
    With no discovery wait the look before the start may or may not see it (discovery on a
    fast host is done within the first spin): then the stray, a second /tug/vessel, is found
    once the run's nodes are up, before step 0. Either look must refuse it, naming it; the
    second look's counting is checked deterministically in-process below."""
    if check_wait == "default":
        monkeypatch.delenv(DOMAIN_CHECK_WAIT_VARIABLE)
    else:
        monkeypatch.setenv(DOMAIN_CHECK_WAIT_VARIABLE, check_wait)
    stray = start_node("tug_dynamics", "vessel_node", "--ros-args", "-r", "__ns:=/tug", "-p",
                       "ship_file:=harbour_tug.yaml", "-p", "lockstep:=true", "-p", "run_id:=old-run")
    time.sleep(3.0)
    out = tmp_path / "refused.mcap"
    proc = subprocess.run(runner(out, "--log-dir", str(tmp_path / "logs")), capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 4, proc.stdout + proc.stderr
    assert "/tug/vessel" in proc.stderr and f"ROS_DOMAIN_ID={ros_domain}" in proc.stderr, proc.stderr
    first_look = "refused to start: " in proc.stderr and "node /tug/vessel (takes /sim/step)" in proc.stderr
    second_look = ("seen once this run's nodes were up; nothing was stepped" in proc.stderr
                   and "2 nodes named /tug/vessel (takes /sim/step)" in proc.stderr)
    assert first_look or second_look, proc.stderr  # (which one sees it depends on discovery's pace)
    assert stray.proc.poll() is None  # the stranger is named, not touched
    assert not out.exists() and "no recording written" in proc.stderr  # nothing that passes for a run


class _Endpoint:
    def __init__(self, node):
        self.node_namespace, self.node_name = node.rsplit("/", 1)


class _Graph:
    """What Conductor.participants_beyond reads of the ROS graph, as given."""

    def __init__(self, step_publishers, step_takers, done_publishers, clock_publishers=("/scenario_runner",)):
        self.graph = {("pub", "/sim/step"): step_publishers, ("sub", "/sim/step"): step_takers,
                      ("pub", "/sim/step_done"): done_publishers, ("pub", "/clock"): clock_publishers}

    def get_fully_qualified_name(self):
        return "/scenario_runner"

    def get_publishers_info_by_topic(self, topic):
        return [_Endpoint(n) for n in self.graph[("pub", topic)]]

    def get_subscriptions_info_by_topic(self, topic):
        return [_Endpoint(n) for n in self.graph[("sub", topic)]]


def test_second_look_counts_a_stranger_sharing_a_name_of_the_run():
    """The look before step 0 allows exactly one of each of the run's nodes: a second /tug/vessel
    (a leftover under the same name) is named, as is another runner or an unknown node."""
    from scenario_runner.conductor import Conductor
    run = ["/tug/vessel", "/barge/vessel", "/towline/rope"]
    clean = _Graph(["/scenario_runner"], run, run)
    assert Conductor.participants_beyond(clean, run) == []
    stray = _Graph(["/scenario_runner"], run + ["/tug/vessel"], run + ["/tug/vessel"])
    assert Conductor.participants_beyond(stray, run) == [
        "2 nodes named /tug/vessel (takes /sim/step): one is not this run's",
        "2 nodes named /tug/vessel (answers on /sim/step_done): one is not this run's"]
    other = _Graph(["/scenario_runner", "/other/scenario_runner"], run + ["/x/vessel"], run)
    assert Conductor.participants_beyond(other, run) == [
        "scenario runner /other/scenario_runner (publishes /sim/step)", "node /x/vessel (takes /sim/step)"]


@pytest.mark.parametrize("layout", ["processes", "one_process"])
def test_sigterm_ends_a_run_like_ctrl_c(tmp_path, ros_domain, layout):
    from mcap.reader import make_reader
    out = tmp_path / "term.mcap"
    log_dir = tmp_path / "logs"
    proc = subprocess.Popen(runner(out, "--log-dir", str(log_dir), "--layout", layout, duration=6000),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if layout == "processes":
        _wait_until_stepping(ros_domain, log_dir)
    else:
        time.sleep(12.0)
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 143, stderr
    assert "interrupted by SIGTERM" in stderr and "Traceback" not in stderr, stderr
    with open(out, "rb") as f:
        assert make_reader(f).get_summary().statistics.message_count > 0  # finalised
    assert _domain_nodes(ros_domain) == []


@pytest.mark.parametrize("moment", ["output claimed", "recording opened"])
def test_a_signal_while_starting_leaves_nothing_behind(tmp_path, ros_domain, moment):
    """Ctrl-C or SIGTERM during the start (before the run loop takes the signals over): no
    traceback, exit 130, and no half-written recording or reserve file left (a 400-byte
    unreadable .mcap and its .reserve were left)."""
    out = tmp_path / "early.mcap"
    watched = tmp_path / (".early.mcap.lock" if moment == "output claimed" else "early.mcap")
    for signum in (signal.SIGINT, signal.SIGTERM):
        proc = subprocess.Popen(runner(out, "--log-dir", str(tmp_path / "logs")), stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 60
        while not watched.exists() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.002)
        proc.send_signal(signum)
        _, stderr = proc.communicate(timeout=60)
        assert proc.returncode in (130, 128 + signum), stderr  # 128 + n: it was already stepping
        assert "Traceback" not in stderr and "interrupted" in stderr, stderr
        assert not (tmp_path / ".early.mcap.reserve").exists() and not (tmp_path / ".early.mcap.lock").exists()
        if out.exists():  # the run had begun: its recording is finalised, not half-written
            from mcap.reader import make_reader
            with open(out, "rb") as f:
                make_reader(f).get_summary()
            out.unlink()
    assert _domain_nodes(ros_domain) == []


def _lockstep_vessel(start_node, run_id="run-x"):
    return start_node("tug_dynamics", "vessel_node", "--ros-args", "-r", "__ns:=/tug", "-p",
                      "ship_file:=harbour_tug.yaml", "-p", "lockstep:=true", "-p", f"run_id:={run_id}")


class Driver:
    """The test as the runner of one vessel node."""

    def __init__(self, rclpy_context, run_id="run-x"):
        from rclpy.node import Node
        from tug_msgs.msg import SimStep, StepDone, VesselCommand, VesselStatus
        from sim_plumbing import ros_common as rc
        self.rc, self.SimStep, self.VesselCommand = rc, SimStep, VesselCommand
        self.run_id = run_id
        self.node = Node("driver", context=rclpy_context)
        self.done, self.status = {}, []
        self.node.create_subscription(StepDone, rc.STEP_DONE_TOPIC,
                                      lambda m: self.done.setdefault(m.step, []).append(m), rc.PROTOCOL_QOS)
        self.node.create_subscription(VesselStatus, "/tug/status", self.status.append, rc.LATCHED_STATE_QOS)
        self.step_pub = self.node.create_publisher(SimStep, rc.SIM_STEP_TOPIC, rc.PROTOCOL_QOS)
        self.cmd_pub = self.node.create_publisher(VesselCommand, "/tug/command", rc.COMMAND_QOS)

    def ready(self, log):
        assert spin_until(self.node, lambda: 0 in self.done and self.step_pub.get_subscription_count() > 0
                          and self.cmd_pub.get_subscription_count() > 0, 60), log()

    def command(self, step, engine, steering=0.0, anchor=0):
        msg = self.VesselCommand(engine_order=engine, steering_angle=steering, anchor=anchor)
        msg.header.stamp = self.rc.step_time(step, 20_000_000)
        self.cmd_pub.publish(msg)

    def trigger(self, step, ordered=()):
        msg = self.SimStep(run_id=self.run_id, step=step, period=0.02, ordered=list(ordered))
        msg.header.stamp = msg.time = self.rc.step_time(step, 20_000_000)
        self.step_pub.publish(msg)


@pytest.fixture
def driver(rclpy_context):
    drivers = []

    def make(run_id="run-x"):
        drivers.append(Driver(rclpy_context, run_id))
        return drivers[-1]
    yield make
    for d in drivers:  # a driver left on the domain would be refused by later runs as a stranger
        d.node.destroy_node()


def test_rejected_announced_order_does_not_stall_the_step(start_node, driver):
    vessel = _lockstep_vessel(start_node)
    d = driver()
    d.ready(vessel.log)
    d.command(0, 0.5)
    d.trigger(0, ["tug"])
    assert spin_until(d.node, lambda: 1 in d.done, 20), vessel.log()
    d.command(1, float("nan"))  # announced for step 1, then refused by the node
    d.trigger(1, ["tug"])
    assert spin_until(d.node, lambda: 2 in d.done, 20), vessel.log()  # answered: no deadlock
    assert d.done[2][0].ok
    assert spin_until(d.node, lambda: d.status and d.status[-1].step == 2, 20)
    assert d.status[-1].commands_rejected == 1 and d.status[-1].engine_order == 0.5  # last valid order held
    assert "command rejected" in vessel.log()


def test_stray_triggers_are_refused_by_the_node(start_node, driver):
    vessel = _lockstep_vessel(start_node)
    d = driver()
    d.ready(vessel.log)
    stranger = Driver.__new__(Driver)
    stranger.__dict__.update(d.__dict__, run_id="other-run")
    stranger.trigger(0)   # another run
    d.run_id, run = "", d.run_id
    d.trigger(0)          # no run id
    d.run_id = run
    d.trigger(5)          # a step the node is not at
    time.sleep(0.5)
    d.trigger(0)
    assert spin_until(d.node, lambda: 1 in d.done, 20), vessel.log()
    assert d.done[1][0].refused_messages == 3
    time.sleep(0.5)
    assert 6 not in d.done and len(d.done[1]) == 1  # nothing stepped on the strays
    assert "refused" in vessel.log()


def test_future_stamped_commands_cannot_grow_the_node(rclpy_context):
    """60,000 orders stamped far ahead are refused and counted; the buffer stays bounded."""
    from rclpy.parameter import Parameter
    from sim_plumbing.cdr import VesselCommandIn
    from sim_plumbing.stepping import MAX_LEAD_STEPS
    from tug_dynamics.vessel_node import VesselNode
    node = VesselNode(context=rclpy_context, namespace="/tug", parameter_overrides=[
        Parameter("ship_file", value="harbour_tug.yaml"), Parameter("lockstep", value=True),
        Parameter("run_id", value="r")])
    try:
        spec = next(s for s in node.inputs if s.topic == "command")
        for i in range(60_000):
            node._on_input(spec, VesselCommandIn((10_000 + i) * node.period_ns, 0.5, 0.0, 0))
        for i in range(50):
            node._on_input(spec, VesselCommandIn((1 + i) * node.period_ns, 0.5, 0.0, 0))
        assert len(node._buffer["command"]) <= MAX_LEAD_STEPS + 1
        assert node.complaints.counts["ahead command"] == 60_000
    finally:
        node.destroy_node()


@pytest.mark.timeout(60)
def test_send_command_refuses_nan(ros_domain, run_in_process):
    """Refused before rclpy is initialised: its entry function in this process (the exit status 2
    through the executable: test_node_processes)."""
    proc = run_in_process("send_command", "tug", "--engine", "nan")
    assert proc.returncode == 2 and "--engine" in proc.stderr and "Traceback" not in proc.stderr


def test_nonfinite_vessel_state_is_named_by_the_vessel_node(start_node, rclpy_context):
    """A force no hull can take (1e300 N) sends the state to inf: the vessel node stops with
    exit 3, naming the vessel and the step, instead of publishing NaN."""
    from geometry_msgs.msg import WrenchStamped
    from rclpy.node import Node
    from sim_plumbing import ros_common as rc
    vessel = start_node("tug_dynamics", "vessel_node", "--ros-args", "-r", "__ns:=/tug", "-p",
                        "ship_file:=harbour_tug.yaml", "-p", "wrench_topics:=[/push]")
    node = Node("pusher", context=rclpy_context)
    pub = node.create_publisher(WrenchStamped, "/push", rc.LATCHED_STATE_QOS)
    assert spin_until(node, lambda: pub.get_subscription_count() > 0, 60), vessel.log()
    msg = WrenchStamped()
    msg.header.frame_id = "tug/base_link"
    msg.wrench.force.x = 1e300
    pub.publish(msg)
    vessel.proc.wait(30)
    node.destroy_node()
    assert vessel.proc.returncode == 3, vessel.log()
    assert "vessel 'tug' diverged at step" in vessel.log() and "not finite" in vessel.log()


@pytest.mark.parametrize("text", ["soon", "-1", "nan", "inf"])
def test_a_bad_domain_check_wait_is_refused_naming_the_variable(monkeypatch, text):
    from scenario_runner.conductor import DOMAIN_CHECK_WAIT_VARIABLE, RunError, domain_discovery_wait
    monkeypatch.setenv(DOMAIN_CHECK_WAIT_VARIABLE, text)
    with pytest.raises(RunError, match=f"{DOMAIN_CHECK_WAIT_VARIABLE}='{text}': expected a number of seconds >= 0"):
        domain_discovery_wait()
    monkeypatch.setenv(DOMAIN_CHECK_WAIT_VARIABLE, "0.5")
    assert domain_discovery_wait() == 0.5
    monkeypatch.delenv(DOMAIN_CHECK_WAIT_VARIABLE)
    assert domain_discovery_wait() == 3.0
