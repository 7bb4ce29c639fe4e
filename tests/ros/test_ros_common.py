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
