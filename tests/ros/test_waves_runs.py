"""Runs in waves (issue 31): the head-seas tow through run_scenario. Two runs of one seed are
identical (one in the process layout, one in one process); a sea of Hs 0 is the calm run exactly;
the hulls heave and pitch in the sea and `status` reports the sea the scenario describes; the
recording's analysis reports the towline's peak over mean and its slack events."""
import json
import math

import numpy as np
import pytest
import yaml

from conftest import entry_function, record_scenario, reserved_domain
from test_recording import decoded

pytestmark = [pytest.mark.ros, pytest.mark.timeout(600)]

DURATION = 45.0        # s simulated: the 30 s ramp and 15 s (two peak periods) of the full sea
TOPICS = ["/tug/odom", "/barge/odom", "/towline/state"]


def _library(name):
    from scenario_format.particulars import scenario_path
    return scenario_path(name)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("waves")
    scenario = yaml.safe_load(open(_library("tow_head_seas")))
    calm_key = dict(scenario, environment={"waves": dict(scenario["environment"]["waves"], hs=0.0)})
    no_waves = dict(scenario, environment={})
    files = {}
    for name, doc in (("hs0", calm_key), ("calm", no_waves)):
        files[name] = base / f"{name}.yaml"
        files[name].write_text(yaml.safe_dump(doc))
    out = {}
    with reserved_domain():
        for name, path, layout in (("waves", _library("tow_head_seas"), "processes"),
                                   ("again", _library("tow_head_seas"), "one_process"),
                                   ("hs0", files["hs0"], "one_process"), ("calm", files["calm"], "one_process")):
            out[name] = base / f"{name}.mcap"
            record_scenario(path, out[name], "--duration", DURATION, layout=layout)
    return out


def _values(path):
    msgs = decoded(path, TOPICS)
    odom = {v: np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z,
                          m.pose.pose.orientation.x, m.pose.pose.orientation.y, m.pose.pose.orientation.z,
                          m.twist.twist.linear.x, m.twist.twist.linear.z, m.twist.twist.angular.y]
                         for m in msgs[f"/{v}/odom"]]) for v in ("tug", "barge")}
    rope = msgs["/towline/state"]
    odom["rope"] = np.array([[p.position.x, p.position.y, p.position.z] for m in rope for p in m.element_poses])
    odom["tension"] = np.array([list(m.connection_tensions) for m in rope])
    return odom


def test_one_seed_one_run_in_either_layout(runs):
    first, again = _values(runs["waves"]), _values(runs["again"])
    for key in first:
        np.testing.assert_array_equal(first[key], again[key], err_msg=key)


def test_a_sea_of_hs_zero_is_the_calm_run_exactly(runs):
    calm, hs0, waves = _values(runs["calm"]), _values(runs["hs0"]), _values(runs["waves"])
    for key in calm:
        np.testing.assert_array_equal(calm[key], hs0[key], err_msg=key)
    assert not np.any(calm["tug"][:, 2]) and not np.any(calm["tug"][:, 4])   # no heave, no pitch
    assert not np.array_equal(calm["tension"], waves["tension"])               # the sea matters


def test_the_hulls_move_in_the_sea_status_reports(runs):
    """After the ramp both hulls heave (odometry z: the manoeuvring z of a displacement hull is 0,
    so z is the wave-frequency heave, which status reports too) and pitch; status carries the
    sea the scenario describes: 4 sqrt(m0) of the same realisation built here from the scenario,
    met from ahead (head seas) at the encounter frequency of the peak, omega_p + k_p U."""
    from sea_environment.environment import Environment
    env, _ = Environment.from_parameter(json.dumps(yaml.safe_load(open(_library("tow_head_seas")))["environment"]))
    hs = 4.0 * math.sqrt(env.waves.m0)
    msgs = decoded(runs["waves"], ["/tug/odom", "/tug/status", "/barge/odom"])
    for v in ("tug", "barge"):
        z = np.array([m.pose.pose.position.z for m in msgs[f"/{v}/odom"]])[-750:]
        assert 0.05 * hs < 4.0 * z.std() < 1.5 * hs, (v, 4.0 * z.std(), hs)
    late = msgs["/tug/status"][-750:]
    odom = {(m.header.stamp.sec, m.header.stamp.nanosec): m for m in msgs["/tug/odom"]}
    wp = 2.0 * math.pi / 7.0
    for st in late[::25]:
        assert st.wave_significant_height == pytest.approx(hs, rel=1e-12)
        assert abs(st.wave_encounter_angle) < math.radians(10.0)
        # head seas: omega_e = omega_p + k_p u cos(angle), |u| the speed through the water (no
        # current here; the tug is still taking the weight, so u is small and of either sign)
        omega_e = 2.0 * math.pi / st.wave_encounter_period
        assert abs(omega_e - wp) <= wp * wp / 9.80665 * st.speed_through_water * 1.001 + 1e-12
        assert st.heave == pytest.approx(odom[(st.header.stamp.sec, st.header.stamp.nanosec)].pose.pose.position.z,
                                         abs=1e-9)
    assert np.std([st.pitch for st in late]) > 0.002


def test_analysis_reports_the_towline_statistics_in_waves(runs, tmp_path, capsys):
    main = entry_function("recording", "analyze")
    assert main([str(runs["waves"]), "-o", str(tmp_path / "an"), "--no-figures", "--quiet"]) in (0, None)
    summary = json.load(open(tmp_path / "an" / "summary.json"))
    end = summary["ropes"]["towline"]["sea_end_a"]
    assert end["tension_max"] >= end["tension_mean"] > 0.0
    assert end["peak_over_mean"] == pytest.approx(end["tension_max"] / end["tension_mean"], rel=1e-9)
    assert isinstance(end["slack_events"], int)
    assert summary["sea"]["window_start"] == pytest.approx(30.0)   # after the scenario's ramp
    # the sea state came with the recording (its particulars), not from a scenario file found later
    assert summary["sea"]["waves"]["hs"] == 2.0 and summary["sea"]["waves"]["scenario"] == "tow_head_seas.yaml"
