"""sim_plumbing.local_bus (in-process hand-over of per-step outputs, issue 33's speed goal):
deliveries posted during a node's step wait until it is over and go out in the order posted, a
delivery that lets another node step does not nest inside it, and a node's handlers end with it.
The runs that use it (interaction in --layout one_process) are checked identical to the process
layout in test_interaction_runs and test_wash_runs; a node switching an input off DDS below."""
import pytest

from sim_plumbing import local_bus


@pytest.fixture(autouse=True)
def clean_bus():
    local_bus.reset()
    yield
    local_bus.reset()


def test_outside_a_step_a_post_is_delivered_at_once_and_only_to_its_topic():
    got = []
    local_bus.subscribe("/a/odom", lambda d: got.append(("a", d)))
    local_bus.subscribe("/b/odom", lambda d: got.append(("b", d)))
    local_bus.post("/a/odom", b"1")
    assert got == [("a", b"1")]
    local_bus.post("/nobody/odom", b"x")  # no handler: nothing kept
    assert got == [("a", b"1")] and not local_bus._pending


def test_posts_during_a_step_wait_for_its_end_and_keep_their_order():
    got = []
    local_bus.subscribe("/t", got.append)
    with local_bus.stepping():
        local_bus.post("/t", b"1")
        local_bus.post("/t", b"2")
        assert got == []            # the publishing node is still in its step
    assert got == [b"1", b"2"]


def test_a_delivery_that_makes_another_node_step_runs_after_not_inside():
    events = []

    def node_b(data):               # b steps on a's output and publishes its own
        events.append(("b in", data))
        with local_bus.stepping():
            local_bus.post("/b/out", b"b" + data)
            events.append(("b out", data))

    local_bus.subscribe("/a/out", node_b)
    local_bus.subscribe("/b/out", lambda d: events.append(("c in", d)))
    with local_bus.stepping():      # node a's step
        local_bus.post("/a/out", b"1")
        events.append(("a done", b""))
    assert events == [("a done", b""), ("b in", b"1"), ("b out", b"1"), ("c in", b"b1")]


def test_an_ended_handler_gets_nothing_more():
    got = []
    end = local_bus.subscribe("/t", got.append)
    local_bus.post("/t", b"1")
    end()
    end()                           # twice: harmless
    local_bus.post("/t", b"2")
    assert got == [b"1"] and not local_bus.has_subscribers("/t")


def test_a_failing_handler_leaves_the_bus_usable():
    got = []

    def broken(data):
        raise RuntimeError("the receiving node's step failed")
    end = local_bus.subscribe("/t", broken)
    with pytest.raises(RuntimeError):
        local_bus.post("/t", b"1")
    end()
    local_bus.subscribe("/t", got.append)
    local_bus.post("/t", b"2")
    assert got == [b"2"]


def test_a_stepped_node_takes_a_local_input_off_dds_and_uses_it_once(rclpy_context):
    """A node in this process publishes what a vessel node takes as a wrench input (local=True):
    the first local copy destroys the vessel's DDS subscription; the copy the wire brought before
    that is the same bytes (nothing changes, nothing refused); the node ends its handler with it."""
    from rclpy.parameter import Parameter
    from test_protocol_trust import _wrench
    from tug_dynamics.vessel_node import VesselNode
    topic = "/interactions/on_tug/wrench"
    node = VesselNode(context=rclpy_context, namespace="/tug", parameter_overrides=[
        Parameter("ship_file", value="harbour_tug.yaml"), Parameter("lockstep", value=True),
        Parameter("run_id", value="r"), Parameter("wrench_topics", value=[topic])])
    try:
        spec = next(s for s in node.inputs if s.topic == topic)
        assert spec.local and local_bus.has_subscribers(topic)
        assert [s for s, _ in node._taken if s.topic_name == topic]
        data = _wrench(node, 0, 1000.0)
        node._on_raw_input(spec, data)          # the wire's copy, before the switch
        local_bus.post(topic, data)             # the same bytes, in-process
        assert not [s for s, _ in node._taken if s.topic_name == topic]   # off DDS
        assert node._buffer[topic][0].force == (0.0, 1000.0, 0.0)
        assert node.untrusted is None and node.complaints.total == 0
        local_bus.post(topic, _wrench(node, 1, 2000.0))                   # the next step's, local only
        assert node._buffer[topic][1].force == (0.0, 2000.0, 0.0)
    finally:
        node.destroy_node()
    assert not local_bus.has_subscribers(topic)
