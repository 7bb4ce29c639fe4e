"""spin_forever ends quietly (saying why) only on what a shutdown raises; anything else propagates."""
import pytest


@pytest.fixture
def context_and_executor(ros_domain):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=ros_domain)
    ex = SingleThreadedExecutor(context=ctx)
    yield ctx, ex
    ex.shutdown()
    ctx.try_shutdown()


def test_a_round_that_runs_into_the_shutdown_ends_the_loop_and_says_so(context_and_executor):
    from rclpy.executors import ExternalShutdownException
    from sim_plumbing.ros_common import spin_forever
    ctx, ex = context_and_executor
    said = []

    def poll():
        ctx.shutdown()
        raise ExternalShutdownException()
    spin_forever(ex, poll, said.append)
    assert said == ["stopped: the last round ran into the shutdown (ExternalShutdownException)"]


def test_an_error_at_shutdown_that_the_shutdown_does_not_raise_propagates(context_and_executor):
    from sim_plumbing.ros_common import spin_forever
    ctx, ex = context_and_executor

    def poll():
        ctx.shutdown()
        raise ValueError("a bug in poll()")
    with pytest.raises(ValueError, match="a bug in poll"):
        spin_forever(ex, poll, print)


def test_the_discovery_profile_is_set_unless_one_is_named(monkeypatch, tmp_path):
    """Every simulator process points Fast DDS at the shipped profile (a participant announces
    itself every 0.5 s), and keeps a profile somebody named (scripts/fastdds_lan.xml on several
    PCs, or a user's)."""
    import os
    import xml.etree.ElementTree as ET
    from sim_plumbing.dds_profile import DDS_PROFILE_VARIABLE, use_discovery_profile
    monkeypatch.delenv(DDS_PROFILE_VARIABLE, raising=False)
    path = use_discovery_profile()
    assert path and path.endswith("fastdds_discovery.xml") and os.environ[DDS_PROFILE_VARIABLE] == path
    ns = {"f": "http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"}
    period = ET.parse(path).getroot().find(".//f:leaseAnnouncement", ns)
    assert int(period.find("f:sec", ns).text) + int(period.find("f:nanosec", ns).text) * 1e-9 == 0.5
    mine = tmp_path / "mine.xml"
    monkeypatch.setenv(DDS_PROFILE_VARIABLE, str(mine))
    assert use_discovery_profile() == str(mine)
