"""Fixtures for tests that start real node processes.

Isolation: every test gets a ROS_DOMAIN_ID reserved with domain_coordinator (a port lock, so
concurrent test runs on one machine never share a domain) and discovery limited to localhost
(ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST). Node processes are started through their installed
executables (ros_ws/install/<pkg>/lib/<pkg>/<exe>, where `ros2 run` looks), their output goes
to a log file that is printed when the test fails, and they are killed at teardown.
"""
from __future__ import annotations

import contextlib
import os
import random
import signal
import socket
import subprocess
import time
from typing import Callable, List

import pytest
from scenario_runner.conductor import DOMAIN_CHECK_WAIT_VARIABLE  # noqa: F401  (tests import it from here)
from scenario_runner.run_nodes import executable_path  # noqa: F401  (tests import it from here)
from sim_plumbing.dds_profile import use_discovery_profile

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.pop("ROS_STATIC_PEERS", None)
os.environ.pop("ROS_LOCALHOST_ONLY", None)  # deprecated in Jazzy; the range above replaces it
use_discovery_profile()  # as the runner and nodes: the test's observers discover as fast as they do




def free_port(kind: int = socket.SOCK_STREAM) -> int:
    """A free port on 127.0.0.1 for a server a test starts (the live view, the station, gpsd).
    Not bind(0): that hands out a port of the kernel's ephemeral range, which the kernel hands
    again to the next outgoing connection of any process, so between this call and the server's
    bind another test's client could take it (ci22: the station never came up, its port taken).
    Below that range instead, and clear of the DDS ports of the first 40 participants of any
    domain (7400 + 250 d + 0..100)."""
    low = int(open("/proc/sys/net/ipv4/ip_local_port_range").read().split()[0])
    for _ in range(1000):
        port = random.randrange(10000, low)
        if (port - 7400) % 250 < 150:
            continue
        with socket.socket(socket.AF_INET, kind) as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    raise RuntimeError("no free port found below the ephemeral range")


class NodeProcess:
    def __init__(self, args: List[str], env: dict, log_path: str):
        self.args = args
        self.log_path = log_path
        self._log = open(log_path, "wb")
        # Own process group, so teardown also reaches anything the node started.
        self.proc = subprocess.Popen(args, env=env, stdout=self._log, stderr=subprocess.STDOUT,
                                     start_new_session=True)

    def log(self) -> str:
        if not self._log.closed:
            self._log.flush()
        with open(self.log_path, "rb") as f:
            return f.read().decode(errors="replace")

    def stop(self, timeout: float = 5.0) -> int:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGINT)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(timeout)
        self._log.close()
        return self.proc.returncode


def processes_of_domain(domain: int) -> List[int]:
    """pids of processes (other than this one) started with ROS_DOMAIN_ID=domain."""
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        try:
            with open(f"/proc/{entry}/environ", "rb") as f:
                env = f.read().split(b"\0")
        except OSError:
            continue
        if f"ROS_DOMAIN_ID={domain}".encode() in env:
            pids.append(int(entry))
    return pids


def kill_processes_of_domain(domain: int) -> List[int]:
    """SIGKILL whatever a test left running in its domain: domains are reused by later tests,
    and a leftover node there is a stranger to their runs (which rightly refuse it)."""
    pids = processes_of_domain(domain)
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    deadline = time.monotonic() + 5.0
    while pids and time.monotonic() < deadline and processes_of_domain(domain):
        time.sleep(0.05)
    return pids


@contextlib.contextmanager
def reserved_domain():
    """A ROS_DOMAIN_ID reserved with domain_coordinator and exported to the processes this one
    starts, until the block ends; then whatever still runs in it is killed and the variable is
    put back. Put back without fail: another worker reserves the domain next, and its clean-up
    kills every process started with it (a process of this worker's later tests included)."""
    from domain_coordinator import domain_id
    old = os.environ.get("ROS_DOMAIN_ID")
    try:
        with domain_id() as did:
            os.environ["ROS_DOMAIN_ID"] = str(did)
            try:
                yield did
            finally:
                kill_processes_of_domain(did)
                # what the killed processes left in /dev/shm (sim_plumbing.shm_hygiene says why)
                from sim_plumbing.shm_hygiene import remove_dead_fastdds_files
                remove_dead_fastdds_files()
    finally:
        if old is None:
            os.environ.pop("ROS_DOMAIN_ID", None)
        else:
            os.environ["ROS_DOMAIN_ID"] = old


_DOMAIN_AT_START = os.environ.get("ROS_DOMAIN_ID")


@pytest.fixture(autouse=True)
def _domain_put_back():
    """A test (or module fixture) that leaves ROS_DOMAIN_ID changed fails, and the variable is
    put back: a leaked domain gets this worker's later processes killed by another worker."""
    yield
    now = os.environ.get("ROS_DOMAIN_ID")
    if now != _DOMAIN_AT_START:
        if _DOMAIN_AT_START is None:
            os.environ.pop("ROS_DOMAIN_ID", None)
        else:
            os.environ["ROS_DOMAIN_ID"] = _DOMAIN_AT_START
        pytest.fail(f"ROS_DOMAIN_ID left at {now} (was {_DOMAIN_AT_START}): use reserved_domain()")


@pytest.fixture
def ros_domain():
    """A reserved ROS_DOMAIN_ID, exported for this test's node processes; whatever still runs
    in it when the test ends is killed before the domain is released."""
    with reserved_domain() as did:
        # the domain is this test's alone: the runner's 3 s look for another run on it (about a
        # sixth of the suite's time) shortened; the tests of that check use full_domain_check
        os.environ[DOMAIN_CHECK_WAIT_VARIABLE] = "0.2"
        try:
            yield did
        finally:
            os.environ.pop(DOMAIN_CHECK_WAIT_VARIABLE, None)


@pytest.fixture
def full_domain_check(ros_domain):
    """The runner's look for another run on the domain as users get it (its default wait; also
    the time an observer in the test process has to match the nodes before step 0)."""
    os.environ.pop(DOMAIN_CHECK_WAIT_VARIABLE, None)
    yield


@pytest.fixture
def start_node(ros_domain, tmp_path, request) -> Callable[..., NodeProcess]:
    """start_node(package, executable, *args) -> NodeProcess in this test's domain."""
    started: List[NodeProcess] = []

    def _start(package: str, executable: str, *args: str, domain: int | None = None) -> NodeProcess:
        env = dict(os.environ, ROS_DOMAIN_ID=str(ros_domain if domain is None else domain),
                   PYTHONUNBUFFERED="1")
        log = tmp_path / f"{executable}-{len(started)}.log"
        node = NodeProcess([executable_path(package, executable), *args], env, str(log))
        started.append(node)
        return node

    yield _start
    failed = getattr(request.node, "rep_call", None) is not None and request.node.rep_call.failed
    for node in started:
        node.stop()
        if failed:
            print(f"----- log of {' '.join(node.args)} -----\n{node.log()}")


# The layout of runs whose tests judge the physics: every node in the runner's process. Its
# recording equals the process layout's number for number (test_recording's and
# test_hull_contact_runs' both-layouts tests; the step protocol makes the layout invisible), and it
# costs a third of the CPU (no interpreter and DDS hop per node; measured 2.7x on the default
# demo), so the two workers of the suite are not starved. Tests of the process layout itself
# (protocol, trust, kills, several hosts, live view, replay) pass layout="processes".
PHYSICS_LAYOUT = "one_process"


def record_scenario(scenario, output, *args, layout: str = PHYSICS_LAYOUT, timeout: float = 600.0,
                    returncode: int | None = 0, env: dict | None = None) -> subprocess.CompletedProcess:
    """run_scenario (its installed console script, a process of its own) on a scenario file or
    library name, recording to `output`, in the caller's ROS_DOMAIN_ID (the ros_domain fixture, or
    reserved_domain() in a module fixture). Asserts the exit status unless returncode is None."""
    proc = subprocess.run([executable_path("scenario_runner", "run_scenario"), str(scenario), "--output",
                           str(output), "--quiet", "--layout", layout, *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, env=env)
    if returncode is not None:
        assert proc.returncode == returncode, f"exit {proc.returncode}:\n{proc.stdout}{proc.stderr}"
    return proc


def entry_function(package: str, executable: str) -> Callable:
    """The function the installed console script `executable` of package calls: its
    console_scripts entry point (setup.py), loaded as the script loads it."""
    from importlib.metadata import distribution
    (entry,) = [e for e in distribution(package.replace("_", "-")).entry_points
                if e.group == "console_scripts" and e.name == executable]
    return entry.load()


class _PastTheChecks(BaseException):
    """Raised by run_in_process's guard when a call gets as far as initialising rclpy (a
    BaseException: no `except Exception` of the code under test takes it for its own error)."""


@pytest.fixture
def run_in_process(capfd, monkeypatch):
    """run_in_process(executable, *args) -> subprocess.CompletedProcess: the scenario_runner (or
    recording: analyze, replay) command line `executable args` run in this process, through the entry function its console
    script calls (sys.exit(main())): the exit status is main's return value (or SystemExit's, as
    argparse raises it), stdout and stderr are what the process would print (file descriptors
    1 and 2, captured). An exception main lets out fails the test, as the process's traceback would.

    Only for what fails before any node starts (bad arguments, files, output paths): while main
    runs, initialising an rclpy context (the first thing each tool does once its checks passed,
    before it makes a node or starts a process) fails the test instead."""
    from rclpy.context import Context

    def guard(self, *args, **kwargs):
        raise _PastTheChecks()

    def _run(executable: str, *args) -> subprocess.CompletedProcess:
        main = entry_function("recording" if executable in ("analyze", "replay") else "scenario_runner", executable)
        argv = [str(a) for a in args]
        capfd.readouterr()
        try:
            with monkeypatch.context() as patch:
                patch.setattr(Context, "init", guard)
                status = main(argv)
        except SystemExit as exc:
            status = exc.code
        except _PastTheChecks:
            err = capfd.readouterr().err
            pytest.fail(f"{executable} {' '.join(argv)}: got past the checks made before any node starts "
                        f"(initialised rclpy); stderr:\n{err}")
        out, err = capfd.readouterr()
        if status is None:
            status = 0
        elif not isinstance(status, int):  # sys.exit("message"): printed, status 1
            err += f"{status}\n"
            status = 1
        return subprocess.CompletedProcess([executable, *argv], status, out, err)

    return _run


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    rep = outcome.get_result()
    setattr(item, "rep_" + rep.when, rep)


@pytest.fixture
def rclpy_context(ros_domain):
    """An rclpy context of this test's domain, for an in-test observer node."""
    import rclpy
    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=ros_domain)
    yield ctx
    # a failed test's traceback holds its nodes: destroyed here, or they would stay in the graph
    # of the domain, which a later test reuses (seen: a later `ros2 param list` asked them)
    import gc
    from rclpy.node import Node
    # type(), not isinstance(): the heap holds weak proxies, and isinstance() of a dead one raises
    for node in [o for o in gc.get_objects() if issubclass(type(o), Node) and o.context is ctx]:
        try:
            node.destroy_node()
        except Exception:  # noqa: BLE001 - destroyed already
            pass
    rclpy.try_shutdown(context=ctx)


def spin_until(node, predicate: Callable[[], bool], timeout: float) -> bool:
    from rclpy.executors import SingleThreadedExecutor
    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    deadline = time.monotonic() + timeout
    try:
        while time.monotonic() < deadline:
            if predicate():
                return True
            executor.spin_once(timeout_sec=0.05)
        return predicate()
    finally:
        executor.remove_node(node)
