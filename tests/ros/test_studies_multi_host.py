"""A study on several machines (issue 35): a Dask scheduler and two workers, each in its own
network namespace with its own address (scripts/hosts_harness.py), the study command on the
scheduler's host given --scheduler. A worker's host dies mid-study (every process on it killed,
its run's run_scenario with it): Dask runs that run again on the other worker and the table is
complete, every run done. Needs root and nft (skipped otherwise)."""
import os
import shutil
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest

from conftest import executable_path

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "scripts"))
import hosts_harness  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300),
              pytest.mark.skipif(hosts_harness.available() is not None,
                                 reason=f"hosts harness: {hosts_harness.available()}")]

STUDY = """
name: several_machines
scenario: default_demo.yaml
duration: 5.0
axes:
  - key: events[0].engine_order
    values: [0.05, 0.2, 0.4, 0.6]
measures:
  peak_tension: ropes.towline.tension_a_max
"""


def _run_on(hosts, host: str):
    """(pid, run id) of a study run's run_scenario on host, or None."""
    r = subprocess.run(["ip", "netns", "pids", hosts.ns(host)], capture_output=True, text=True)
    for pid in r.stdout.split():
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                args = f.read().decode(errors="replace").split("\0")
        except OSError:
            continue
        if any(a.endswith("run_scenario") for a in args):
            scenario = next(a for a in args if a.endswith("scenario.yaml"))
            return int(pid), os.path.basename(os.path.dirname(scenario))
    return None


def _kill_host(hosts, host: str) -> None:
    """The host dies: its Dask processes first (had the run's process died first, the worker would
    have lived to report it as a failed run, which a machine that dies never does), then the run."""
    r = subprocess.run(["ip", "netns", "pids", hosts.ns(host)], capture_output=True, text=True)
    for pid in r.stdout.split():
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                if b"run_scenario" not in f.read():
                    os.kill(int(pid), signal.SIGKILL)
        except OSError:
            pass
    hosts_harness.kill_namespace_processes(hosts.ns(host))


def _wait(condition, timeout, what):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.2)
    raise AssertionError(f"no {what} within {timeout} s")


def test_a_worker_killed_mid_study_has_its_run_made_elsewhere(tmp_path):
    study = tmp_path / "study.yaml"
    study.write_text(STUDY)
    out = tmp_path / "out"
    dask = shutil.which("dask")
    env = {k: v for k, v in os.environ.items() if k != "ROS_DOMAIN_ID"}
    env["PYTHONUNBUFFERED"] = "1"
    with hosts_harness.Hosts(["sched", "w1", "w2"]) as hosts:
        address = f"tcp://{hosts.addresses['sched']}:8786"
        logs = {name: open(tmp_path / f"{name}.log", "wb") for name in ("sched", "w1", "w2", "study")}
        hosts.popen("sched", [dask, "scheduler", "--host", hosts.addresses["sched"], "--port", "8786",
                              "--no-dashboard"], env=env, stdout=logs["sched"], stderr=subprocess.STDOUT)
        # the namespaces share /dev/shm (Fast DDS discovers over it) and this machine's other ROS
        # work takes domains 1-100: each worker's runs a range of their own
        for w, domains in (("w1", "150-169"), ("w2", "170-189")):
            hosts.popen(w, [dask, "worker", address, "--host", hosts.addresses[w], "--nthreads", "1",
                            "--no-dashboard", "--name", w], env=dict(env, TUGSIM_STUDY_DOMAINS=domains),
                        stdout=logs[w], stderr=subprocess.STDOUT)
        for w in ("w1", "w2"):  # both workers with the scheduler before the study starts
            _wait(lambda: b"Registered to" in (tmp_path / f"{w}.log").read_bytes(), 60, f"{w} registered")
        study_cmd = [executable_path("studies", "study"), str(study), "-o", str(out), "--scheduler", address, "--quiet"]
        proc = hosts.popen("sched", study_cmd, env=env, stdout=logs["study"], stderr=subprocess.STDOUT)
        pid, killed_run = _wait(lambda: _run_on(hosts, "w1"), 120, "run on w1")
        time.sleep(1.0)  # well into the run
        _kill_host(hosts, "w1")
        status = proc.wait(240)
        text = (tmp_path / "study.log").read_text()
        assert status == 0, text + (tmp_path / "sched.log").read_text()[-3000:]
    table = pd.read_parquet(out / "results.parquet")
    assert len(table) == 4 and list(table["status"]) == ["ok"] * 4, table
    assert table["peak_tension"].notna().all()
    w2 = f"tcp://{hosts.addresses['w2']}:"
    again = table[table["run"] == killed_run].iloc[0]
    assert again["host"].startswith(w2), (killed_run, table[["run", "host"]])
    assert "dask: 2 worker(s)" in text and "dashboard" in text
