"""At the controls (issue 32): a paced run driven by a person through the console, the instructor
page and send_command, started as docs/bridge-instruments.md's console recipe writes it (its two
lines taken from the page: the run shortened to DURATION s with its output in the test's folder,
and `--live` added for the page on free ports).

- the console's helm key (5 deg port) takes the helm, not the engine the console sends with it
  (the held 0.05, followed exactly);
- the page's "Half ahead" takes the engine, not the helm it sends with it (the held value);
- send_command --steering-deg -10 alone takes the helm and leaves the engine;
- every manual order stays in force in the recording until the person changes it: the script's
  engine steps at 40, 45 and 50 s yield (`scripted_order_yielded`), each take is announced
  (`manual_order`) naming who may have given it (the publishers of the command topic).
"""
import math
import os
import re
import shlex
import shutil
import subprocess

import numpy as np
import pytest

from conftest import executable_path
from test_instructor_station import _free_port, _open_page, _wait_http, _wait_page, browser  # noqa: F401

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

PAGE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "docs", "bridge-instruments.md")
DURATION = 52.0


def _console_recipe():
    """The two command lines of the page's Console section (without '&' and comments)."""
    text = open(PAGE).read()
    section = text[text.index("## Console"):]
    block = re.search(r"```bash\n(.*?)```", section, re.S).group(1)
    return [shlex.split(line.split("#")[0].rstrip().rstrip("&")) for line in block.splitlines() if line.strip()]


def _wait_console_time(con, t: float) -> float:
    """Read the console's screen until its simulation time is at least t; that time."""
    while True:
        con.expect(r"t +(\d+\.\d\d) s ", timeout=60)
        now = float(con.match.group(1))
        if now >= t:
            return now


def _run_by_hand(tmp_path, browser, out):  # noqa: F811
    import pexpect
    run_line, console_line = _console_recipe()
    assert "--realtime" in run_line and "default_demo.yaml" in run_line, run_line
    http_port = _free_port()
    run_argv = [shutil.which(run_line[0]), *run_line[1:]]
    run_argv[run_argv.index("--output") + 1] = str(out)
    run = subprocess.Popen([*run_argv, "--duration", str(DURATION), "--quiet", "--live", "--live-port",
                            str(_free_port()), "--ros-args", "-p", f"live_view:http_port:={http_port}"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    con = pexpect.spawn(shutil.which(console_line[0]), console_line[1:], dimensions=(50, 160), timeout=60,
                        encoding="utf-8", cwd=str(tmp_path))
    said = {}
    try:
        con.expect(r"rate of turn", timeout=120)
        _wait_console_time(con, 4.0)
        con.send("a")                                  # helm 5 deg to port
        said["console"] = _wait_console_time(con, 0.0)
        url = f"http://127.0.0.1:{http_port}/"
        _wait_http(url, run)
        page, errors = _open_page(browser, url)
        _wait_page(page, "instructor.snap && instructor.snap.t > 10 && "
                         "Math.abs(instructor.snap.vessels.tug.steering_ordered_deg - 5) < 1e-6")
        said["page"] = page.evaluate("instructor.snap.t")
        page.click("#engine-half")                     # engine 0.5; the helm as held
        _wait_page(page, "document.getElementById('answer').textContent.includes('sent')", 20)
        _wait_page(page, "instructor.snap.t > 16")
        sent = subprocess.run([executable_path("scenario_runner", "send_command"), "tug", "--steering-deg", "-10"],
                              capture_output=True, text=True, timeout=60)
        assert sent.returncode == 0, sent.stderr
        said["send_command"] = float(re.search(r"stamped (\d+\.\d+) s", sent.stdout).group(1))
        assert not errors, errors
        stdout, stderr = run.communicate(timeout=120)
        assert run.returncode == 0, stderr
    finally:
        con.sendcontrol("c")
        con.close(force=True)
        if run.poll() is None:
            run.kill()
    return said


def test_a_person_at_the_console_the_page_and_send_command_stays_in_command(tmp_path, ros_domain, browser):  # noqa: F811
    out = tmp_path / "drive.mcap"
    said = _run_by_hand(tmp_path, browser, out)
    assert said["console"] < said["page"] < said["send_command"] < 40.0, said

    from recording.recorded_run import Recording, status_column
    rec = Recording(str(out))
    st = rec.vessels["tug"]["status"]
    t, engine = st["t"], status_column(st, "engine_order")
    helm = np.degrees(status_column(st, "steering_angle_ordered"))
    t_helm = t[np.argmax(np.abs(helm - 5.0) < 1e-6)]
    t_engine = t[np.argmax(engine == 0.5)]
    t_sc = t[np.argmax(np.abs(helm + 10.0) < 1e-6)]
    assert t_helm < t_engine < t_sc, (t_helm, t_engine, t_sc)
    # each order in force until the person's next one, through the script's engine steps
    span = lambda a, b: (t >= a) & (t < b)  # noqa: E731
    assert np.all(np.abs(helm[span(t_helm, t_sc)] - 5.0) < 1e-6)
    assert np.all(np.abs(helm[t >= t_sc] + 10.0) < 1e-6)
    assert np.all(engine[span(t_helm, t_engine)] == 0.05)      # the console's key left the engine
    assert np.all(engine[t >= t_engine] == 0.5)                # the page's order, to the end
    assert t[-1] >= DURATION - 0.1

    ev = [(e["time"], e["kind"], e["detail"]) for e in rec.events]
    takes = [(d.split(":")[0], d) for _, k, d in ev if k == "manual_order"]
    assert [c for c, _ in takes] == ["tug helm", "tug engine", "tug helm"], takes
    # who: named from the ROS graph's publishers of /tug/command (all of them once several are up)
    for (_, detail), who in zip(takes, ("/console", "/live_view", "/send_command")):
        assert who in detail.split("manual order by")[1] and "yields" in detail, (who, detail)
    yielded = sorted(round(tt, 2) for tt, k, _ in ev if k == "scripted_order_yielded")
    assert yielded == [40.0, 45.0, 50.0], yielded
    assert math.isclose(said["send_command"], t_sc, abs_tol=1.0), (said, t_sc)
