"""nmea_out started by hand beside a running run, exactly as docs/bridge-instruments.md writes it:
the two lines of its first bash block, taken from the page and run as written, except that the
run is shortened (`--duration`, an output in the test's folder, `--quiet` appended) and the
sentences go to the test's own UDP port instead of 10110 (which another program may hold):

- the node given only `scenario` and `outputs` sends what the run's scenario says it should:
  the towline's tension ($IIXDR,N,...,towline) and the barge's AIS static data with the length
  and beam of its ship file (read here with yaml), with no warning of anything lacking;
- the same node without `scenario` (the vessels given) runs too and says in its log what it
  cannot send: no tension sentences, AIS static data without dimensions; and sends none.
"""
import os
import re
import shlex
import shutil
import signal
import subprocess
import time

import pytest
import yaml

from test_nmea_out import Listener, _ship_path

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

PAGE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "docs", "bridge-instruments.md")
DOC_PORT = "127.0.0.1:10110"


def _documented_commands():
    """The command lines of the page's first bash block (without a trailing '&')."""
    text = open(PAGE).read()
    block = re.search(r"```bash\n(.*?)```", text, re.S).group(1)
    return [shlex.split(line.rstrip().rstrip("&")) for line in block.splitlines() if line.strip()]


def _start(argv, log_path):
    argv = [shutil.which(argv[0]) or argv[0], *argv[1:]]
    log = open(log_path, "wb")
    return subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, start_new_session=True,
                            env=dict(os.environ, PYTHONUNBUFFERED="1"))


def _interrupt(proc):
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGINT)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(5)


def _wait_for(path, text, proc, timeout):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if text in (open(path).read() if os.path.exists(path) else ""):
            return
        assert proc.poll() is None, open(path).read()
        time.sleep(0.1)
    pytest.fail(f"{text!r} not in {path} within {timeout:g} s:\n{open(path).read()}")


def _sentences(datagrams):
    import pyais
    nmea, ais, parts = [], [], []
    for d in datagrams:
        line = d.decode("ascii").rstrip("\r\n")
        if line.startswith("!"):
            parts.append(line.encode())
            if line.split(",")[1] == line.split(",")[2]:
                ais.append(pyais.decode(*parts).asdict())
                parts = []
        else:
            nmea.append(line)
    return nmea, ais


def test_nmea_out_started_as_the_docs_write_it(tmp_path, ros_domain):
    run_argv, nmea_argv = _documented_commands()
    assert run_argv[:4] == ["ros2", "run", "scenario_runner", "run_scenario"], run_argv
    assert nmea_argv[:4] == ["ros2", "run", "bridge_instruments", "nmea_out"], nmea_argv
    documented, bare = Listener(), Listener()
    assert sum(DOC_PORT in a for a in nmea_argv) == 1, nmea_argv
    as_written = [a.replace(DOC_PORT, f"127.0.0.1:{documented.port}") for a in nmea_argv]
    # the same without the scenario: the vessels named instead
    scenario_arg = next(a for a in nmea_argv if a.startswith("scenario:="))
    without = [a.replace(DOC_PORT, f"127.0.0.1:{bare.port}") for a in nmea_argv]
    without[without.index(scenario_arg)] = "vessels:=['tug','barge']"
    nodes, logs = [], [tmp_path / "nmea_documented.log", tmp_path / "nmea_bare.log"]
    run = None
    try:
        for argv, log in zip((as_written, without), logs):
            nodes.append(_start(argv, log))
        for node, log in zip(nodes, logs):
            _wait_for(log, "NMEA 0183 / AIS out", node, 60)
        run = _start([*run_argv, "--duration", "40", "--output", str(tmp_path / "by_hand.mcap"), "--quiet"],
                     tmp_path / "run.log")
        run.wait(240)
    finally:
        if run is not None:
            _interrupt(run)
        for node in nodes:
            _interrupt(node)
        documented.close()
        bare.close()
    assert run.returncode == 0, open(tmp_path / "run.log").read()
    log, bare_log = (open(p).read() for p in logs)
    assert "WARN" not in log and "ERROR" not in log, log
    nmea, ais = _sentences(documented.datagrams)
    tensions = [float(line.split(",")[2]) for line in nmea if line.startswith("$IIXDR,N,") and ",towline*" in line]
    assert len(tensions) >= 10 and min(tensions) > 10.0, (len(nmea), tensions[:5])  # the hanging line pulls
    hull = yaml.safe_load(open(_ship_path("barge_002_full.yaml")))["hull"]
    static = [m for m in ais if m["msg_type"] == 5]
    assert static and all(m["shipname"] == "BARGE" for m in static)
    assert {(m["to_bow"] + m["to_stern"], m["to_port"] + m["to_starboard"]) for m in static} == \
        {(round(hull["length"]), round(hull["beam"]))}
    # without the scenario: said in its log, and nothing sent that it could not know
    assert "no 'scenario'" in bare_log and "no tension sentences" in bare_log, bare_log
    assert "barge" in bare_log and "no length, beam or draught" in bare_log, bare_log
    nmea, ais = _sentences(bare.datagrams)
    assert len(nmea) >= 50 and not any(line.startswith("$IIXDR,N,") for line in nmea), nmea[:12]
    assert all(m["to_bow"] + m["to_stern"] <= 1 for m in ais if m["msg_type"] == 5)
