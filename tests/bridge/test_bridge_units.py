"""ROS-free checks of the human / equipment edge: geodesy (pymap3d against a closed-form local
radius check), NMEA field formats parsed back by pynmea2, AIS by pyais, the console's order
state under invalid keys and joystick noise, and the scenario's human-unit keys."""
import math

import pytest

from bridge_instruments import controls
from bridge_instruments import sentences as S
from sim_contract import geo
from sim_contract.equipment import parse_utc


def test_enu_geodetic_round_trip_and_scale():
    o = geo.DEFAULT_ORIGIN
    lat, lon, _ = geo.enu_to_geodetic(1000.0, 2000.0, o)
    e, n, _ = geo.geodetic_to_enu(lat, lon, o)
    assert abs(e - 1000.0) < 1e-3 and abs(n - 2000.0) < 1e-3
    # independent: WGS-84 meridian and prime-vertical radii at the origin (1 km: error < 1 m)
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    phi = math.radians(o.latitude)
    m = a * (1 - e2) / (1 - e2 * math.sin(phi) ** 2) ** 1.5
    nr = a / math.sqrt(1 - e2 * math.sin(phi) ** 2)
    assert abs(math.radians(lat - o.latitude) * m - 2000.0) < 1.0
    assert abs(math.radians(lon - o.longitude) * nr * math.cos(phi) - 1000.0) < 1.0


def test_headings_and_knots():
    assert geo.compass_deg(0.0) == 90.0 and geo.compass_deg(math.pi / 2) == 0.0
    assert geo.yaw_deg_from_compass(90.0) == 0.0
    assert geo.knots(1852.0 / 3600.0) == pytest.approx(1.0)
    assert geo.course_over_ground(1.0, 0.0) == 90.0
    assert geo.rate_of_turn(math.radians(1.0)) == pytest.approx(-60.0)  # port turn: negative


def test_sentences_parse_with_pynmea2():
    import pynmea2
    u = parse_utc("2026-06-01T23:59:59.98Z")
    own = S.OwnShip(0.0, -33.5, -70.25, 12.345, 359.999, 0.0, 30.0, -20.0, -150.0, -750.0, (("tow", 1234.5),))
    lines = S.own_ship_sentences(own, u)
    msgs = [pynmea2.parse(line, check=True) for line in lines]
    assert all(len(line) + 2 <= S.MAX_SENTENCE for line in lines)
    rmc, gga = msgs[0], msgs[1]
    assert rmc.lat_dir == "S" and rmc.lon_dir == "W" and rmc.true_course == 0.0
    assert rmc.latitude == pytest.approx(-33.5, abs=1e-9) and gga.longitude == pytest.approx(-70.25, abs=1e-9)
    assert str(rmc.timestamp).startswith("23:59:59.98")
    assert [m.sentence_type for m in msgs] == ["RMC", "GGA", "VTG", "HDT", "ROT", "RSA", "RPM", "RPM", "XDR"]
    # with an attitude: one more XDR at the end, the others unchanged
    with_att = S.own_ship_sentences(own._replace(pitch_deg=-0.04, roll_deg=12.35), u)
    assert with_att[:-1] == lines
    att = pynmea2.parse(with_att[-1], check=True)
    assert [tuple(att.get_transducer(i)) for i in range(2)] == [("A", "0.0", "D", "PTCH"), ("A", "12.3", "D", "ROLL")]


def test_ais_target_round_trip():
    import pyais
    tg = S.Target(244990002, 51.98, 4.05, 200.0, 10.0, 359.7, -5000.0)
    d = pyais.decode(*S.position_report(tg, 3.0, parse_utc("2026-06-01T08:00:00Z"))).asdict()
    assert d["speed"] == 102.2 and d["heading"] == 0 and d["second"] == 3  # clipped / wrapped
    assert d["turn"] < 0 and abs(d["lat"] - 51.98) < 1e-5
    s = pyais.decode(*S.static_report(S.Particulars(244990002, "barge", 45.4, 12.6, 2.0))).asdict()
    assert s["to_bow"] + s["to_stern"] == 45 and s["to_port"] + s["to_starboard"] == 13


def test_console_orders_stay_in_range():
    o = controls.Orders(max_helm_deg=35.0)
    for key in ["z", "F1", "escape", "ctrl+x", "", "9"]:
        assert o.key(key) is None
    for _ in range(50):
        o.key("w")
        o.key("left")
    assert o.engine == 1.0 and o.helm_deg == 35.0
    for _ in range(50):
        o.key("s")
        o.key("d")
    assert o.engine == -1.0 and o.helm_deg == -35.0
    import random
    rnd = random.Random(1)
    noise = [float("nan"), float("inf"), -float("inf"), 1e300, -1e300, "x", None]
    for _ in range(2000):
        a = rnd.choice(noise + [rnd.uniform(-3, 3)])
        b = rnd.choice(noise + [rnd.uniform(-3, 3)])
        o.joystick(a, b)
        assert -1.0 <= o.engine <= 1.0 and -35.0 <= o.helm_deg <= 35.0
        assert math.isfinite(o.engine) and math.isfinite(o.helm_deg)
    o.joystick(0.01, -0.02)  # inside the dead zone
    assert o.engine == 0.0 and o.helm_deg == 0.0


def test_warnings_near_limits():
    assert controls.warnings(0.5, 0.7, 0.0, None) == []
    assert controls.warnings(0.6, 0.7, 0.0, None)[0].startswith("GIRTING")
    assert controls.warnings(0.0, 0.7, 130e3, 156.9e3)[0].startswith("TENSION")


def test_scenario_human_units(tmp_path):
    from scenario_format.scenario import ScenarioError, load_scenario
    text = """
name: h
duration: 1.0
origin: {latitude: 53.54, longitude: 9.97}
vessels:
  - name: tug
    ship_file: harbour_tug.yaml
    initial: {latitude: 53.541, longitude: 9.971, heading_true_deg: 45.0, speed_kn: 10.0}
nmea: {outputs: [{vessel: tug}], mmsi: {tug: 211000001}}
"""
    p = tmp_path / "h.yaml"
    p.write_text(text)
    sc = load_scenario(str(p), check_files=False)
    v = sc.vessels[0].initial
    assert v.heading_deg == 45.0 and v.speed == pytest.approx(10 * 1852 / 3600)
    e, n, _ = geo.geodetic_to_enu(53.541, 9.971, geo.Origin(53.54, 9.97))
    assert (v.x, v.y) == (pytest.approx(e), pytest.approx(n))
    assert sc.nmea.outputs[0].port == 10110 and sc.nmea.outputs[0].host == "127.0.0.1"
    for bad in ("heading_true_deg: 45.0, heading_deg: 0.0", "heading_true_deg: 400.0", "speed_kn: .nan",
                "latitude: 53.5"):
        p.write_text(text.replace("latitude: 53.541, longitude: 9.971, heading_true_deg: 45.0, speed_kn: 10.0", bad))
        with pytest.raises(ScenarioError):
            load_scenario(str(p), check_files=False)
    for bad in ("mmsi: {tug: 12}", "mmsi: {barge: 211000001}", "outputs: [{vessel: tug, port: 0}], rate: 1.0"):
        p.write_text(text.replace("mmsi: {tug: 211000001}", bad) if "mmsi" in bad else
                     text.replace("outputs: [{vessel: tug}], mmsi: {tug: 211000001}", bad))
        with pytest.raises(ScenarioError):
            load_scenario(str(p), check_files=False)


def test_ais_dimensions_honour_the_scenarios_ship_overrides(tmp_path):
    """A scenario that lengthens and widens the barge: the AIS type 5 of the barge (pyais)
    gives the overridden length and beam, the tug (no overrides) its ship file's."""
    import pyais
    import yaml
    from scenario_format.particulars import hull_dimensions, scenario_ships
    from tug_dynamics.ship_file import ships_dir
    barge_file = yaml.safe_load(open(f"{ships_dir()}/barge_002_full.yaml"))["hull"]
    tug_file = yaml.safe_load(open(f"{ships_dir()}/harbour_tug.yaml"))["hull"]
    assert (barge_file["length"], barge_file["beam"]) != (60.0, 18.4)  # the override changes something
    sc = {"name": "o", "duration": 1.0,
          "vessels": [{"name": "tug", "ship_file": "harbour_tug.yaml"},
                      {"name": "barge", "ship_file": "barge_002_full.yaml", "initial": {"x": -100.0},
                       "ship_overrides": {"hull": {"length": 60.0, "beam": 18.4}}}]}
    path = tmp_path / "o.yaml"
    path.write_text(yaml.safe_dump(sc))
    ships = scenario_ships(str(path))
    assert ships["tug"][1] == {} and ships["barge"][1] == {"hull": {"length": 60.0, "beam": 18.4}}
    barge = hull_dimensions(*ships["barge"])
    tug = hull_dimensions(*ships["tug"])
    assert (barge.length, barge.beam, barge.draft) == (60.0, 18.4, barge_file["draft"])  # the rest stays
    assert (tug.length, tug.beam) == (tug_file["length"], tug_file["beam"])
    s = pyais.decode(*S.static_report(S.Particulars(244990002, "barge", barge.length, barge.beam,
                                                    barge.draft))).asdict()
    assert s["to_bow"] + s["to_stern"] == 60 and s["to_port"] + s["to_starboard"] == 18
    # bad input names the file
    with pytest.raises(ValueError, match="no_such_ship.yaml"):
        hull_dimensions("no_such_ship.yaml")
    with pytest.raises(ValueError, match="ship_overrides must be a mapping"):
        hull_dimensions("harbour_tug.yaml", ["hull"])
    path.write_text("name: o\nvessels: 3\n")
    with pytest.raises(ValueError, match="o.yaml"):
        scenario_ships(str(path))


@pytest.mark.parametrize("compass, yaw_deg", [(0.0, 90.0), (90.0, 0.0), (180.0, -90.0), (270.0, -180.0),
                                              (360.0, 90.0), (45.0, 45.0), (359.5, 90.5)])
def test_autopilot_heading_order_in_compass_degrees(compass, yaw_deg):
    """The example autopilot's heading_true_deg (compass, deg true) becomes the REP-103 yaw the
    controller keeps (rad, 0 = east, counter-clockwise; the law wraps the heading error, so any
    equal direction will do): checked against hand values and back
    through sim_math.trials.compass_deg (what HDT and the console show), within 1e-9 deg."""
    from scenario_runner.autopilot import heading_from_true_deg
    from sim_math.trials import compass_deg
    yaw = heading_from_true_deg(compass)
    assert abs((math.degrees(yaw) - yaw_deg + 180.0) % 360.0 - 180.0) < 1e-9  # the same direction
    back = compass_deg(yaw)
    assert abs((back - compass + 180.0) % 360.0 - 180.0) < 1e-9


@pytest.mark.parametrize("bad", [-0.1, 360.5, float("nan"), float("inf"), True, "90", None])
def test_autopilot_heading_order_refuses_what_is_no_compass_heading(bad):
    from scenario_runner.autopilot import heading_from_true_deg
    with pytest.raises(ValueError, match="heading_true_deg"):
        heading_from_true_deg(bad)
