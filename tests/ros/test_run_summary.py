"""run_scenario's summary for people (scenario_runner.run_summary), in process: the tension with
its share of the rope file's breaking load, the final position as latitude / longitude from the
scenario's origin and as metres of it, the heading in deg true, the speed in knots; the runner's
developer notes go to the log folder, not to the summary."""
import math
from types import SimpleNamespace

import pytest

pytestmark = pytest.mark.ros

SCENARIO = """\
name: summary_case
duration: 10.0
exchange_rate: 20.0
mode: lockstep
origin: {latitude: 51.98, longitude: 4.05}
vessels:
  - name: tug
    ship_file: harbour_tug.yaml
    initial: {x: 0.0, y: 0.0, heading_deg: 0.0, speed: 0.0}
  - name: barge
    ship_file: box_barge_000.yaml
    initial: {x: -125.0, y: 0.0, heading_deg: 0.0, speed: 0.0}
ropes:
  - {name: towline, rope_file: table1.yaml, end_a: tug/towing_hook, end_b: barge/bow_bollard, layout: straight}
"""
WGS84_A, WGS84_F = 6378137.0, 1 / 298.257223563


def _odometry(x, y, yaw, speed):
    from nav_msgs.msg import Odometry
    od = Odometry()
    od.pose.pose.position.x, od.pose.pose.position.y = x, y
    od.pose.pose.orientation.z, od.pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    od.twist.twist.linear.x = speed
    return od


def test_summary_for_people(tmp_path):
    from scenario_format.scenario import load_scenario
    from scenario_runner import conductor as cd
    from scenario_runner import run_summary
    path = tmp_path / "summary_case.yaml"
    path.write_text(SCENARIO)
    sc = load_scenario(str(path))
    stats = cd.RunStats(steps_done=200, wall_time=4.0, rescued=2)
    # the tug 1000 m east of the origin heading north-east (yaw 45 deg) at 5 m/s; the barge at
    # the origin heading east, stopped
    mon = SimpleNamespace(tension={"towline": [10_000.0, 46_800.0, 20_000.0]}, broken={"towline": False},
                          odom={"tug": _odometry(1000.0, 0.0, math.radians(45.0), 5.0),
                                "barge": _odometry(0.0, -250.0, 0.0, 0.0)})
    text = run_summary.summary(sc, stats, mon)
    lines = [line.strip() for line in text.splitlines()]
    assert lines[0] == "scenario 'summary_case': 10.0 s simulated in 4.0 s wall (2.5x real time, 200 steps at 20 Hz, " \
                       "lockstep)", text
    # Table 1's rope: breaking load 156.9064 kN; 46.8 / 156.9 = 29.8 %; mean 25.6 kN
    assert "towline: tension peak 46.8 kN (30 % of MBL 157 kN), mean 25.6 kN" in lines, text
    # 1000 m east of 51.98 N: the longitude grows by 1000 m / (N cos(lat)), N the WGS-84 prime
    # vertical radius of curvature (the tangent plane's east axis, to a few cm at 1 km)
    e2 = WGS84_F * (2 - WGS84_F)
    lat = math.radians(51.98)
    n = WGS84_A / math.sqrt(1 - e2 * math.sin(lat) ** 2)
    dlon_min = math.degrees(1000.0 / (n * math.cos(lat))) * 60.0
    lon_min = 3.0 + dlon_min  # 4 deg 03.000' E + that
    tug = next(line for line in lines if line.startswith("tug: "))
    assert tug.startswith(f"tug: final position 51°58.800'N 4°{lon_min:06.3f}'E (1000.0 m E, 0.0 m N of origin), "
                          "heading 45.0 deg true, speed 9.72 kn"), (tug, lon_min)
    barge = next(line for line in lines if line.startswith("barge: "))
    # 250 m south: one minute of latitude is the meridian arc M = a (1 - e2) / (1 - e2 sin^2)^1.5 per rad
    m = WGS84_A * (1 - e2) / (1 - e2 * math.sin(lat) ** 2) ** 1.5
    lat_min = 58.8 - math.degrees(250.0 / m) * 60.0
    assert barge == f"barge: final position 51°{lat_min:06.3f}'N 4°03.000'E (0.0 m E, 250.0 m S of origin), " \
                    "heading 90.0 deg true, speed 0.00 kn", (barge, lat_min)
    # the developer's line is not for people: it goes to the log folder
    assert "StepDone" not in text and "executor" not in text, text
    notes = run_summary.write_runner_notes(str(tmp_path / "logs"), stats)
    assert "2 StepDone(s) the executor held back" in open(notes).read()
    assert run_summary.write_runner_notes(str(tmp_path / "logs2"), cd.RunStats()) is None
    # a parted line says so; a rope without a breaking load gives the tension alone
    import numpy as np
    assert run_summary.tension_line("towline", np.array([157_100.0, 0.0, 0.0]), 156_906.4, True) == \
        "towline: tension peak 157.1 kN (100 % of MBL 157 kN), mean 52.4 kN, PARTED"
    assert run_summary.tension_line("spring", np.array([1000.0]), None, False) == \
        "spring: tension peak 1.0 kN, mean 1.0 kN"
