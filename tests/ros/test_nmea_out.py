"""NMEA 0183 and AIS out (bridge_instruments nmea_out, started by the scenario key `nmea`) in a
paced run, read by independent parsers and compared with the recording of the same steps:

- every datagram on the test's own UDP socket is one sentence; every NMEA sentence parses with
  pynmea2 with its checksum checked, is at most 82 characters, and has the expected talker;
  every AIS sentence decodes with pyais (multi-part type 5 assembled);
- per report (an RMC and the sentences up to the next), the RMC / GGA time names the step
  (UTC = utc_start + t), and against that step's recorded messages: the position converted
  back to ENU metres (pymap3d) within 0.5 m, course and speed over ground from the recorded
  body-frame velocity rotated with scipy, heading = (90 - yaw) mod 360, rate of turn, rudder,
  shaft rpm and towline tension (the recorded rope state's end force); the barge as an AIS
  target: position within 0.5 m, speed, course, heading, and its type 5 dimensions equal the
  length and beam of its hull in the run: the ship file's with the scenario's ship_overrides
  (a longer, wider barge);
- bad destinations (an invalid host name, a broadcast address the socket may not send to) are
  each reported once in the node's log and the run completes with every step recorded.
"""
import math
import os
import signal
import socket
import subprocess
import threading
import time

import pytest
import yaml

from conftest import executable_path, processes_of_domain
from test_recording import decoded

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

DURATION = 15.0
RATE = 5.0
ORIGIN = (53.5400, 9.9700)  # not the default: the key must be used
UTC_START = "2026-03-04T05:06:07Z"
BARGE_HULL = {"length": 48.0, "beam": 16.0}  # ship_overrides of the barge (its file: 45.0 x 15.003 m)


def _scenario(tmp_path, port):
    from ament_index_python.packages import get_package_share_directory
    share = get_package_share_directory("scenario_runner")
    sc = dict(yaml.safe_load(open(f"{share}/scenarios/default_demo.yaml")), name="nmea", mode="realtime",
              duration=DURATION)
    # the tug given at the human edge: compass heading and knots (90 deg true = REP-103 yaw 0)
    sc["vessels"][0]["initial"] = {"x": 0.0, "y": 0.0, "heading_true_deg": 90.0, "speed_kn": 1.0}
    sc["events"] = [{"time": 0.0, "vessel": "tug", "engine_order": 0.6},
                    {"time": 3.0, "vessel": "tug", "steering_deg": 25.0}]
    sc["origin"] = {"latitude": ORIGIN[0], "longitude": ORIGIN[1]}
    # AIS must report the hull of the run, not the ship file's
    sc["vessels"][1]["ship_overrides"] = {"hull": dict(BARGE_HULL)}
    sc["nmea"] = {"rate": RATE, "utc_start": UTC_START, "static_every": 5, "mmsi": {"barge": 244123456},
                  "outputs": [{"vessel": "tug", "host": "127.0.0.1", "port": port},
                              {"vessel": "tug", "host": "bad host!", "port": 10110},
                              {"vessel": "tug", "host": "255.255.255.255", "port": 10110}]}
    path = tmp_path / "nmea.yaml"
    path.write_text(yaml.safe_dump(sc))
    return path, sc


class Listener:
    def __init__(self):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.datagrams = []
        self.stop = False
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        while not self.stop:
            try:
                self.datagrams.append(self.sock.recv(4096))
            except socket.timeout:
                pass

    def close(self):
        self.stop = True
        self.thread.join()
        self.sock.close()


def _reports(datagrams):
    """[(RMC, [NMEA sentences], [AIS messages])] in arrival order, parsed by pynmea2 / pyais."""
    import pyais
    import pynmea2
    reports, parts = [], []
    for d in datagrams:
        assert d.endswith(b"\r\n") and d.count(b"\r\n") == 1, d  # one sentence per datagram
        line = d.decode("ascii").rstrip("\r\n")
        assert len(line) + 2 <= 82, line
        if line.startswith("!"):
            parts.append(line.encode())
            n, i = int(line.split(",")[1]), int(line.split(",")[2])
            if i == n:
                reports[-1][2].append(pyais.decode(*parts).asdict())
                parts = []
            continue
        msg = pynmea2.parse(line, check=True)
        # heading and engine talkers: the defaults (II), which gpsd reads (test_nmea_gpsd.py)
        assert msg.talker == {"RMC": "GP", "GGA": "GP", "VTG": "GP", "HDT": "II", "ROT": "II", "RSA": "II",
                              "RPM": "II", "XDR": "II"}[msg.sentence_type], line
        if msg.sentence_type == "RMC":
            reports.append((msg, [], []))
        else:
            reports[-1][1].append(msg)
    return reports


def _truth(rec, vessel, step, period_ns):
    """What the sentences of a step should say, from the recording, computed here (scipy)."""
    from scipy.spatial.transform import Rotation
    stamp = step * period_ns
    od = next(m for m in rec[f"/{vessel}/odom"] if m.header.stamp.sec * 10**9 + m.header.stamp.nanosec == stamp)
    st = next(m for m in rec[f"/{vessel}/status"] if m.header.stamp.sec * 10**9 + m.header.stamp.nanosec == stamp)
    q = od.pose.pose.orientation
    rot = Rotation.from_quat([q.x, q.y, q.z, q.w])
    tw = od.twist.twist
    ve, vn, _ = rot.apply([tw.linear.x, tw.linear.y, tw.linear.z])
    yaw = rot.as_euler("ZYX")[0]
    w_world = rot.apply([tw.angular.x, tw.angular.y, tw.angular.z])
    return {"x": od.pose.pose.position.x, "y": od.pose.pose.position.y, "sog": math.hypot(ve, vn) * 3600 / 1852,
            "cog": math.degrees(math.atan2(ve, vn)) % 360, "hdg": (90 - math.degrees(yaw)) % 360,
            "rot": -math.degrees(w_world[2]) * 60, "rudder": -math.degrees(st.steering_angle),
            "rpm": st.shaft_speed * 60 / (2 * math.pi), "roll": math.degrees(st.heel + st.roll),
            "pitch": math.degrees(st.trim + st.pitch)}


def _angle_diff(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


def test_nmea_and_ais_out_of_a_paced_run(tmp_path, ros_domain):
    import datetime as dt
    import pymap3d
    listener = Listener()
    path, sc = _scenario(tmp_path, listener.port)
    out = tmp_path / "nmea.mcap"
    try:
        done = subprocess.run([executable_path("scenario_runner", "run_scenario"), str(path), "--output", str(out),
                               "--quiet"], capture_output=True, text=True, timeout=240)
    finally:
        listener.close()
    assert done.returncode == 0, done.stderr
    log = (tmp_path / "nmea_logs" / "bridge_nmea_out.log").read_text()
    # bad destinations: each reported exactly once, the run went on (every step recorded)
    assert log.count("'bad host!'") == 1 and "is invalid" in log, log
    assert log.count("255.255.255.255:10110 for 'tug' refuses") == 1, log
    rec = decoded(str(out), [f"/{v}/{t}" for v in ("tug", "barge") for t in ("odom", "status")]
                  + ["/towline/state"])
    n_steps = int(DURATION * 50)
    assert len(rec["/tug/odom"]) == n_steps + 1

    reports = _reports(listener.datagrams)
    assert len(reports) >= 0.8 * DURATION * RATE, len(reports)
    period_ns = 20_000_000
    start = dt.datetime.fromisoformat(UTC_START.replace("Z", "+00:00"))
    rope_state = {m.step: m for m in rec["/towline/state"]}
    barge_file = yaml.safe_load(open(_ship_path("barge_002_full.yaml")))["hull"]
    assert (round(barge_file["length"]), round(barge_file["beam"])) != (BARGE_HULL["length"], BARGE_HULL["beam"])
    checked = {"course": 0, "rot": 0, "tension": 0, "ais": 0, "static": 0}
    steps_seen = []
    for rmc, rest, ais in reports:
        kinds = [m.sentence_type for m in rest]
        assert kinds[:7] == ["GGA", "VTG", "HDT", "ROT", "RSA", "RPM", "RPM"] and kinds[7:] == ["XDR", "XDR"], kinds
        gga, vtg, hdt, rot, rsa, rpm_e, rpm_s, xdr, att = rest
        when = dt.datetime.combine(rmc.datestamp, rmc.timestamp)
        t = (when - start).total_seconds()
        step = round(t * 50)
        assert abs(t - step * 0.02) < 1e-6 and step % int(50 / RATE) == 0, t
        assert gga.timestamp == rmc.timestamp
        steps_seen.append(step)
        truth = _truth(rec, "tug", step, period_ns)
        for fix in (gga, rmc):
            e, n, _ = pymap3d.geodetic2enu(fix.latitude, fix.longitude, 0.0, *ORIGIN, 0.0)
            assert math.hypot(e - truth["x"], n - truth["y"]) < 0.5, (step, e, n, truth)
        assert abs(float(rmc.spd_over_grnd) - truth["sog"]) <= 0.006
        assert abs(float(vtg.spd_over_grnd_kts) - truth["sog"]) <= 0.006
        if truth["sog"] > 0.3:
            assert _angle_diff(float(rmc.true_course), truth["cog"]) <= 0.02
            assert _angle_diff(float(vtg.true_track), truth["cog"]) <= 0.02
            checked["course"] += 1
        assert _angle_diff(float(hdt.heading), truth["hdg"]) <= 0.006 and hdt.hdg_true == "T"
        assert abs(float(rot.rate_of_turn) - truth["rot"]) <= 0.006 + 0.01 * abs(truth["rot"]), (step, rot, truth)
        checked["rot"] += abs(truth["rot"]) > 5.0
        assert abs(float(rsa.rsa_starboard) - truth["rudder"]) <= 0.006 and rsa.rsa_starboard_status == "A"
        assert rpm_e.source == "E" and rpm_s.source == "S"
        assert abs(float(rpm_s.speed) - truth["rpm"]) <= 0.06
        f = rope_state[step].end_a_force
        tension = math.sqrt(f.x ** 2 + f.y ** 2 + f.z ** 2)
        # the attitude: pitch bow up +, roll starboard down + (REP-103 pitch is bow down +)
        assert [att.get_transducer(i)[::2] for i in range(2)] == [("A", "D"), ("A", "D")], att
        assert [att.get_transducer(i).id for i in range(2)] == ["PTCH", "ROLL"], att
        assert abs(float(att.get_transducer(0).value) + truth["pitch"]) <= 0.051, (step, att, truth)
        assert abs(float(att.get_transducer(1).value) - truth["roll"]) <= 0.051, (step, att, truth)
        assert xdr.type == "N" and xdr.units == "N" and xdr.id == "towline"
        assert abs(float(xdr.value) - tension) <= 0.06 + 1e-6 * tension, (step, xdr, tension)
        checked["tension"] += tension > 100.0
        # the barge as an AIS target
        barge = _truth(rec, "barge", step, period_ns)
        pos = [m for m in ais if m["msg_type"] == 1]
        assert len(pos) == 1 and pos[0]["mmsi"] == 244123456
        p = pos[0]
        e, n, _ = pymap3d.geodetic2enu(p["lat"], p["lon"], 0.0, *ORIGIN, 0.0)
        assert math.hypot(e - barge["x"], n - barge["y"]) < 0.5
        assert abs(p["speed"] - barge["sog"]) <= 0.051 and p["second"] == when.second
        assert _angle_diff(p["heading"], barge["hdg"]) <= 0.51
        if barge["sog"] > 0.3:
            assert _angle_diff(p["course"], barge["cog"]) <= 0.051
        checked["ais"] += 1
        for s in (m for m in ais if m["msg_type"] == 5):
            assert s["mmsi"] == 244123456 and s["shipname"] == "BARGE"
            assert s["to_bow"] + s["to_stern"] == BARGE_HULL["length"]
            assert s["to_port"] + s["to_starboard"] == BARGE_HULL["beam"]
            checked["static"] += 1
    assert steps_seen == sorted(steps_seen) and len(set(steps_seen)) == len(steps_seen)
    # the run turned, moved and pulled: the comparisons above were not of zeros
    assert checked["course"] > 20 and checked["rot"] > 20 and checked["tension"] > 20, checked
    assert checked["static"] >= len(reports) // 5, checked


def _ship_path(name):
    from ament_index_python.packages import get_package_share_directory
    return f"{get_package_share_directory('tug_dynamics')}/ships/{name}"


def test_a_run_whose_instrument_dies_stops_naming_it(tmp_path, ros_domain):
    """nmea_out is part of the run the user asked for: it ending mid-run (here killed) stops the
    run with exit 3 naming it and its log, as a node's death does (it once went unnoticed: exit 0)."""
    path, sc = _scenario(tmp_path, 9)  # port 9 (discard): the sentences go nowhere
    run = subprocess.Popen([executable_path("scenario_runner", "run_scenario"), str(path), "--output",
                            str(tmp_path / "dies.mcap"), "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
    try:
        deadline = time.monotonic() + 120
        log = tmp_path / "dies_logs" / "bridge_nmea_out.log"
        while time.monotonic() < deadline and "NMEA 0183 / AIS out" not in (log.read_text() if log.exists() else ""):
            time.sleep(0.1)
        [pid] = [p for p in processes_of_domain(ros_domain) if b"nmea_out" in open(f"/proc/{p}/cmdline", "rb").read()]
        os.kill(pid, signal.SIGKILL)
        stdout, stderr = run.communicate(timeout=60)
    finally:
        if run.poll() is None:
            run.kill()
    assert run.returncode == 3, stderr
    assert "instrument /bridge/nmea_out died (exit code -9)" in stderr and str(log) in stderr, stderr


def test_attitude_sentence_of_a_status_message():
    """$IIXDR pitch / roll from a tug_msgs/VesselStatus, in process: the totals (heel + roll,
    trim + pitch), REP-103 pitch (bow down +) turned into the bus's bow up +, roll (starboard
    down +) kept; the checksum and fields as pynmea2 parses them."""
    import pynmea2
    from tug_msgs.msg import VesselStatus
    from bridge_instruments.nmea_out import attitude
    from bridge_instruments import sentences as S
    st = VesselStatus(heel=math.radians(2.0), roll=math.radians(1.25), trim=math.radians(0.5),
                      pitch=math.radians(-3.0))
    pitch, roll = attitude(st)
    assert pitch == pytest.approx(2.5) and roll == pytest.approx(3.25)  # bow up 2.5 deg, starboard down 3.25
    line = S.attitude_xdr(pitch, roll)
    assert line == "$IIXDR,A,2.5,D,PTCH,A,3.2,D,ROLL*" + line.rsplit("*", 1)[1], line  # 3.25 -> 3.2 (half-even)
    msg = pynmea2.parse(line, check=True)
    assert msg.talker == "II" and msg.sentence_type == "XDR" and msg.num_transducers == 2
    assert tuple(msg.get_transducer(0)) == ("A", "2.5", "D", "PTCH")
    assert tuple(msg.get_transducer(1)) == ("A", "3.2", "D", "ROLL")
    # a calm, level vessel heeled to port and trimmed by the head
    st = VesselStatus(heel=math.radians(-4.0), trim=math.radians(1.0))
    assert S.attitude_xdr(*attitude(st)).startswith("$IIXDR,A,-1.0,D,PTCH,A,-4.0,D,ROLL*")
    with pytest.raises(pynmea2.ChecksumError):
        pynmea2.parse(line[:-2] + ("00" if line[-2:] != "00" else "01"), check=True)


def test_heading_and_engine_talkers_are_chosen_and_checked():
    """The talkers of HDT / ROT and RPM: II by default (gpsd 3.22 drops HE and ER), any valid
    two-character talker when chosen (a gyro's HE, the engine room's ER); a talker that is not
    two upper-case letters or digits, or a proprietary P..., is refused naming it."""
    import datetime as dt
    import pynmea2
    from bridge_instruments import sentences as S
    ship = S.OwnShip(1.0, 51.98, 4.05, 5.0, 45.0, 44.0, 12.0, -3.0, 100.0, 520.0)
    start = dt.datetime(2026, 3, 4, tzinfo=dt.timezone.utc)
    talkers = {pynmea2.parse(line, check=True).sentence_type: line[1:3] for line in S.own_ship_sentences(ship, start)}
    assert (talkers["HDT"], talkers["ROT"], talkers["RPM"]) == ("II", "II", "II")
    chosen = [pynmea2.parse(line, check=True) for line in S.own_ship_sentences(ship, start, S.Talkers("HE", "ER"))]
    assert [(m.talker, m.sentence_type) for m in chosen if m.sentence_type in ("HDT", "ROT", "RPM")] == \
        [("HE", "HDT"), ("HE", "ROT"), ("ER", "RPM"), ("ER", "RPM")]
    assert float(chosen[3].heading) == 44.0
    assert S.check_talker("GP") is None and S.check_talker("I1") is None
    for bad in ("", "H", "he", "HEX", "PG", "H-"):
        assert S.check_talker(bad) and repr(bad) in S.check_talker(bad), bad
