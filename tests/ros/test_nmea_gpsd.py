"""NMEA out read by Debian's gpsd (3.22, Debian 12), the way a chart plotter or a logger behind
gpsd gets a run: the tow of tests/ros/test_nmea_out.py with NMEA to a UDP port gpsd reads
(`gpsd -N -n -b -S <port> -F <own control socket> udp://127.0.0.1:<port>`, in the foreground,
killed at the end), and `gpspipe -w` reporting what gpsd made of it:

- TPV with a fix (3D once a GGA came), position, speed and track, and ATT with the heading (the default heading
  talker, II: gpsd drops $HEHDT), each compared with the recorded odometry of the step the TPV's
  time names (UTC = utc_start + t): position within 0.5 m (pymap3d back to ENU), speed within
  0.007 kn (RMC's 0.01 kn and gpsd's 0.001 m/s), track within 0.02 deg, heading within 0.006 deg;
- AIS (gpsd's own decoding of !AIVDM, class "AIS", unscaled ITU-R M.1371 units converted here):
  the barge's type 1 reports (position within 0.5 m, speed 0.1 kn, course 0.1 deg, heading 1 deg
  steps) and type 5 static data (name, MMSI, the run's hull: 48 x 16 m).

gpsd and gpspipe come from Debian (apt-get install gpsd gpsd-clients); the test installs them
when missing (as root, waiting for apt's lock) and fails naming the command where it cannot.
"""
import datetime as dt
import json
import math
import os
import shutil
import signal
import socket
import subprocess
import time

import pytest
import yaml

from conftest import executable_path, free_port
from test_nmea_out import BARGE_HULL, DURATION, ORIGIN, RATE, UTC_START, _angle_diff, _scenario, _truth
from test_recording import decoded

pytestmark = [pytest.mark.ros, pytest.mark.timeout(1200)]

KNOT = 1852.0 / 3600.0  # m/s
APT = ["apt-get", "-o", "DPkg::Lock::Timeout=300", "-o", "Acquire::Retries=3"]


def _ensure_gpsd():
    if shutil.which("gpsd") and shutil.which("gpspipe"):
        return
    assert os.geteuid() == 0 and shutil.which("apt-get"), \
        "gpsd and gpspipe are missing: apt-get install gpsd gpsd-clients (Debian 12: gpsd 3.22)"
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    install = APT + ["install", "-y", "-qq", "gpsd", "gpsd-clients"]
    done = subprocess.run(install, env=env, capture_output=True, text=True, timeout=900)
    if done.returncode != 0:
        subprocess.run(APT + ["update", "-qq"], env=env, capture_output=True, timeout=600)
        done = subprocess.run(install, env=env, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0 and shutil.which("gpsd") and shutil.which("gpspipe"), \
        f"{' '.join(install)} failed:\n{done.stdout[-2000:]}{done.stderr[-2000:]}"


def _free_port(kind) -> int:
    return free_port(kind)


def _stop(proc):
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(5)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(5)


def _watch_until_ready(gpsd_port, gpsd, timeout=20.0):
    """gpspipe -w on gpsd's port, once gpsd answers there."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert gpsd.poll() is None, gpsd.communicate()
        try:
            socket.create_connection(("127.0.0.1", gpsd_port), timeout=1).close()
            break
        except OSError:
            time.sleep(0.1)
    return subprocess.Popen(["gpspipe", "-w", f"localhost:{gpsd_port}"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, start_new_session=True)


def _by_step(reports):
    """gpsd's JSON objects grouped under the step the latest TPV's time names (ATT and AIS carry
    no time: they follow the TPV of their report in the stream)."""
    start = dt.datetime.fromisoformat(UTC_START.replace("Z", "+00:00"))
    steps, step = {}, None
    for r in reports:
        if r["class"] == "TPV" and r.get("time"):
            t = (dt.datetime.fromisoformat(r["time"].replace("Z", "+00:00")) - start).total_seconds()
            step = round(t * 50)
            assert abs(t - step * 0.02) < 1e-6, r
        if step is not None and r["class"] in ("TPV", "ATT", "AIS"):
            steps.setdefault(step, []).append(r)
    return steps


def test_gpsd_reports_fix_speed_track_heading_and_ais(tmp_path, ros_domain):
    import pymap3d
    _ensure_gpsd()
    udp_port, gpsd_port = _free_port(socket.SOCK_DGRAM), _free_port(socket.SOCK_STREAM)
    path, sc = _scenario(tmp_path, udp_port)
    sc["nmea"]["outputs"] = [{"vessel": "tug", "host": "127.0.0.1", "port": udp_port}]
    path.write_text(yaml.safe_dump(sc))
    gpsd = subprocess.Popen(["gpsd", "-N", "-n", "-b", "-S", str(gpsd_port), "-F", str(tmp_path / "gpsd.sock"),
                             f"udp://127.0.0.1:{udp_port}"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            start_new_session=True)
    pipe = None
    out = tmp_path / "gpsd.mcap"
    try:
        pipe = _watch_until_ready(gpsd_port, gpsd)
        done = subprocess.run([executable_path("scenario_runner", "run_scenario"), str(path), "--output", str(out),
                               "--quiet"], capture_output=True, text=True, timeout=240)
        time.sleep(1.0)  # gpsd's last reports reach gpspipe
    finally:
        if pipe is not None:
            _stop(pipe)
        _stop(gpsd)
    assert done.returncode == 0, done.stderr
    assert gpsd.returncode is not None and pipe.returncode is not None  # both ended here
    reports = [json.loads(line) for line in pipe.stdout.read().decode().splitlines() if line.startswith("{")]
    steps = _by_step(reports)
    rec = decoded(str(out), [f"/{v}/{t}" for v in ("tug", "barge") for t in ("odom", "status")])
    period_ns = 20_000_000
    checked = {"3d": 0, "tpv": 0, "track": 0, "att": 0, "ais1": 0, "ais5": 0}
    for step, objs in sorted(steps.items()):
        tug, barge = _truth(rec, "tug", step, period_ns), _truth(rec, "barge", step, period_ns)
        for r in objs:
            if r["class"] == "TPV":
                assert r["mode"] in (2, 3), r  # 2D from an RMC alone, 3D once a GGA came
                checked["3d"] += r["mode"] == 3
                e, n, _ = pymap3d.geodetic2enu(r["lat"], r["lon"], 0.0, *ORIGIN, 0.0)
                assert math.hypot(e - tug["x"], n - tug["y"]) < 0.5, (step, r, tug)
                assert abs(r["speed"] / KNOT - tug["sog"]) <= 0.007, (step, r, tug)
                if tug["sog"] > 0.3:
                    assert _angle_diff(r["track"], tug["cog"]) <= 0.02, (step, r, tug)
                    checked["track"] += 1
                checked["tpv"] += 1
            elif r["class"] == "ATT":
                assert _angle_diff(r["heading"], tug["hdg"]) <= 0.006, (step, r, tug)
                checked["att"] += 1
            elif r["type"] == 1:
                assert r["mmsi"] == 244123456 and r["scaled"] is False, r
                # ITU-R M.1371 units: 1/10000 minute, 0.1 kn, 0.1 deg
                e, n, _ = pymap3d.geodetic2enu(r["lat"] / 600000.0, r["lon"] / 600000.0, 0.0, *ORIGIN, 0.0)
                assert math.hypot(e - barge["x"], n - barge["y"]) < 0.5, (step, r, barge)
                assert abs(r["speed"] / 10.0 - barge["sog"]) <= 0.051, (step, r, barge)
                assert _angle_diff(r["heading"], barge["hdg"]) <= 0.51, (step, r, barge)
                if barge["sog"] > 0.3:
                    assert _angle_diff(r["course"] / 10.0, barge["cog"]) <= 0.051, (step, r, barge)
                checked["ais1"] += 1
            elif r["type"] == 5:
                assert r["mmsi"] == 244123456 and r["shipname"] == "BARGE", r
                assert r["to_bow"] + r["to_stern"] == BARGE_HULL["length"], r
                assert r["to_port"] + r["to_starboard"] == BARGE_HULL["beam"], r
                checked["ais5"] += 1
    print(checked)
    reports_sent = DURATION * RATE
    # every report of the run reached gpsd's clients as a fix, a heading and a target
    assert checked["3d"] >= 0.8 * reports_sent, checked
    assert checked["tpv"] >= 0.8 * reports_sent and checked["att"] >= 0.8 * reports_sent, checked
    assert checked["track"] >= 0.5 * reports_sent and checked["ais1"] >= 0.8 * reports_sent, checked
    assert checked["ais5"] >= 2, checked
