"""Every input a node would refuse is refused before any node starts.

A corpus of malformed scenarios (and of the ship and rope files they name), each run as the
command line `run_scenario <file> --no-record --quiet` in this process: the entry function the
executable calls (run_scenario.main, which refuses in plan_run, before rclpy is initialised),
with its stdout and stderr captured. Each must exit 2 with a message naming the file and the
key, without a traceback, and start nothing (no node log directory is created; the runner makes
it only when it starts the nodes; rclpy is not initialised). One case also goes through the
real executable, a process of its own, end to end.
"""
import os
import subprocess

import pytest

from conftest import executable_path

pytestmark = [pytest.mark.ros]

SRC = os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src")
SHIPS = os.path.join(SRC, "tug_dynamics", "ships")
ROPES = os.path.join(SRC, "rope_model", "ropes")

BASE = """\
name: malformed_base
description: "base of the malformed-input corpus: valid as written"
duration: 2.0
exchange_rate: 50.0
environment: {current: [0.0, 0.0], water_density: 1025.0}
vessels:
  - name: tug
    ship_file: harbour_tug.yaml
    initial: {x: 0.0, y: 0.0, heading_deg: 0.0, speed: 0.0}
  - name: barge
    ship_file: barge_002_full.yaml
    initial: {x: -80.0, y: 5.0, heading_deg: 10.0, speed: 0.0}
ropes:
  - name: towline
    rope_file: table1.yaml
    end_a: tug/winch_aft
    end_b: barge/bow_bollard
    layout: winch
    deployed_length: 60.0
events:
  - {time: 0.5, rope: towline, payout_rate: 0.5}
  - {time: 1.0, vessel: barge, anchor: heave_up}
autopilots:
  - name: pilot
    vessel: tug
    params: {mode: heading, heading: 90.0, speed_control: true, speed: 2.0}
"""


def _ship(name, *edits):
    return ("ship", name, edits)


def _rope(name, *edits):
    return ("rope", name, edits)


# id: (scenario edits [(old, new)], extra files {file name: ("ship" | "rope", source, edits) or text},
#      texts stderr must contain besides the scenario file)
CASES = {
    # --- values the vessel node's parameter ranges refuse
    "heading_720deg": ([("heading_deg: 0.0", "heading_deg: 720.0")], {}, ["vessels[0].initial.heading_deg", "720"]),
    "heading_minus_400deg": ([("heading_deg: 10.0", "heading_deg: -400.0")], {}, ["vessels[1].initial.heading_deg"]),
    "x_2e7": ([("x: 0.0", "x: 2.0e+7")], {}, ["vessels[0].initial.x"]),
    "y_minus_1e8": ([("y: 5.0", "y: -1.0e+8")], {}, ["vessels[1].initial.y"]),
    "x_nan": ([("x: 0.0", "x: .nan")], {}, ["vessels[0].initial.x", "finite"]),
    "speed_inf": ([("speed: 0.0}\n  - name: barge", "speed: .inf}\n  - name: barge")], {},
                  ["vessels[0].initial.speed"]),
    "steering_120deg": ([("speed: 0.0}\n  - name: barge", "speed: 0.0, steering_deg: 120.0}\n  - name: barge")], {},
                        ["vessels[0].initial.steering_deg"]),
    "engine_order_bool": ([("speed: 0.0}\n  - name: barge", "speed: 0.0, engine_order: true}\n  - name: barge")],
                          {}, ["vessels[0].initial.engine_order"]),
    "current_100ms": ([("current: [0.0, 0.0]", "current: [100.0, 0.0]")], {}, ["environment.current"]),
    "current_nan": ([("current: [0.0, 0.0]", "current: [0.0, .nan]")], {}, ["environment.current"]),
    "current_three_numbers": ([("current: [0.0, 0.0]", "current: [0.0, 0.0, 0.0]")], {}, ["environment.current"]),
    "water_density_1e-9": ([("water_density: 1025.0", "water_density: 1.0e-9")], {}, ["environment.water_density"]),
    "depth_negative": ([("current: [0.0, 0.0]", "current: [0.0, 0.0], depth: -4.0")], {}, ["environment.depth"]),
    "depth_grid_missing": ([("current: [0.0, 0.0]", "current: [0.0, 0.0], depth: {grid: nowhere.asc}")], {},
                           ["environment.depth.grid", "nowhere.asc", "not found"]),
    "depth_grid_negative_entry": ([("current: [0.0, 0.0]", "current: [0.0, 0.0], depth: {grid: bad.asc}")],
                                  {"bad.asc": "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n"
                                              "5.0 6.0\n5.0 -2.0\n"},
                                  ["environment.depth.grid", "bad.asc: line 7, column 2: depth -2.0 m is negative"]),
    "wind_without_direction": ([("current: [0.0, 0.0]", "current: [0.0, 0.0], wind: {speed_kn: 20.0}")], {},
                               ["environment.wind.from_deg"]),
    "turn_rate_100deg_s": ([("speed: 0.0}\n  - name: barge", "speed: 0.0}\n    motion: {type: turn, speed: 2.0, "
                             "turn_rate_deg: 100.0, turn_duration: 10.0}\n  - name: barge")], {},
                           ["vessels[0].motion.turn_rate_deg"]),
    # --- duration and rate
    "duration_inf": ([("duration: 2.0", "duration: .inf")], {}, ["'duration'"]),
    "duration_nan": ([("duration: 2.0", "duration: .nan")], {}, ["'duration'"]),
    "duration_negative": ([("duration: 2.0", "duration: -5.0")], {}, ["'duration'"]),
    "duration_zero": ([("duration: 2.0", "duration: 0")], {}, ["'duration'"]),
    "duration_text": ([("duration: 2.0", "duration: two seconds")], {}, ["'duration'"]),
    "duration_under_one_step": ([("duration: 2.0", "duration: 0.001")], {}, ["'duration'", "one step"]),
    "exchange_rate_1e6": ([("exchange_rate: 50.0", "exchange_rate: 1.0e+6")], {}, ["'exchange_rate'"]),
    # --- YAML itself
    "unknown_key": ([("speed: 0.0}\n  - name: barge", "speeed: 0.0}\n  - name: barge")], {},
                    ["vessels[0].initial.speeed", "unknown key"]),
    "unknown_top_key": ([("duration: 2.0", "duraton: 2.0")], {}, ["'duraton'"]),
    "duplicate_top_key": ([("exchange_rate: 50.0", "exchange_rate: 50.0\nduration: 500.0")], {},
                          ["duplicate key 'duration'", "line 5"]),
    "duplicate_flow_key": ([("{x: 0.0,", "{x: 0.0, x: 5.0,")], {}, ["duplicate key 'x'", "line 9"]),
    "invalid_yaml_indent": ([("    ship_file: harbour_tug.yaml", "   ship_file: harbour_tug.yaml")], {},
                            ["not valid YAML", "line 8"]),
    "invalid_yaml_unclosed": ([("current: [0.0, 0.0]", "current: [0.0, 0.0")], {}, ["not valid YAML", "line"]),
    "top_level_list": ([(BASE, "- name: x\n- duration: 1\n")], {}, ["top level"]),
    # --- ship files
    "ship_file_missing": ([("harbour_tug.yaml", "no_such_tug.yaml")], {}, ["vessels[0].ship_file", "not found"]),
    "ship_mass_1e30": ([("harbour_tug.yaml", "bad_ship.yaml")],
                       {"bad_ship.yaml": _ship("harbour_tug.yaml", ("mass: 295200.0", "mass: 1.0e+30"))},
                       ["vessels[0].ship_file", "bad_ship.yaml", "hull.mass"]),
    "ship_mass_1e-9": ([("harbour_tug.yaml", "bad_ship.yaml")],
                       {"bad_ship.yaml": _ship("harbour_tug.yaml", ("mass: 295200.0", "mass: 1.0e-9"))},
                       ["vessels[0].ship_file", "bad_ship.yaml", "hull.mass"]),
    "ship_engine_time_constant_1e-9": ([("harbour_tug.yaml", "bad_ship.yaml")],
                                       {"bad_ship.yaml": _ship("harbour_tug.yaml",
                                                               ("time_constant: 4.0", "time_constant: 1.0e-9"))},
                                       ["vessels[0].ship_file", "engine.time_constant"]),
    "ship_water_density_1e-9": ([("barge_002_full.yaml", "bad_barge.yaml")],
                                {"bad_barge.yaml": _ship("barge_002_full.yaml",
                                                         ("water_density: 1025.0", "water_density: 1.0e-9"))},
                                ["vessels[1].ship_file", "bad_barge.yaml", "water_density"]),
    "ship_max_substep_1e-7": ([("harbour_tug.yaml", "bad_ship.yaml")],
                              {"bad_ship.yaml": _ship("harbour_tug.yaml", ("max_substep: 0.1", "max_substep: 1.0e-7"))},
                              ["vessels[0].ship_file", "integration.max_substep"]),
    "ship_length_nan": ([("harbour_tug.yaml", "bad_ship.yaml")],
                        {"bad_ship.yaml": _ship("harbour_tug.yaml", ("length: 24.0", "length: .nan"))},
                        ["vessels[0].ship_file", "hull.length"]),
    "ship_duplicate_key": ([("harbour_tug.yaml", "bad_ship.yaml")],
                           {"bad_ship.yaml": _ship("harbour_tug.yaml",
                                                   ("  beam: 8.0\n", "  beam: 8.0\n  beam: 80.0\n"))},
                           ["vessels[0].ship_file", "bad_ship.yaml", "duplicate key 'beam'", "line"]),
    "ship_invalid_yaml": ([("harbour_tug.yaml", "bad_ship.yaml")],
                          {"bad_ship.yaml": _ship("harbour_tug.yaml", ("  beam: 8.0\n", "  beam: [8.0\n"))},
                          ["vessels[0].ship_file", "bad_ship.yaml", "not valid YAML", "line"]),
    "ship_unknown_key": ([("harbour_tug.yaml", "bad_ship.yaml")],
                         {"bad_ship.yaml": _ship("harbour_tug.yaml", ("  beam: 8.0\n", "  beam: 8.0\n  beem: 8.0\n"))},
                         ["vessels[0].ship_file", "hull.beem", "unknown key"]),
    "ship_required_key_missing": ([("harbour_tug.yaml", "bad_ship.yaml")],
                                  {"bad_ship.yaml": _ship("harbour_tug.yaml", ("  beam: 8.0\n", ""))},
                                  ["vessels[0].ship_file", "hull.beam", "missing"]),
    "ship_number_as_text": ([("harbour_tug.yaml", "bad_ship.yaml")],
                            {"bad_ship.yaml": _ship("harbour_tug.yaml", ("diameter: 2.0", "diameter: big"))},
                            ["vessels[0].ship_file", "propellers.0.diameter"]),
    "planing_mass_nan": ([("harbour_tug.yaml", "bad_boat.yaml")],
                         {"bad_boat.yaml": _ship("planing_40ft.yaml", ("mass: 18900.0", "mass: .nan"))},
                         ["vessels[0].ship_file", "bad_boat.yaml", "hull.mass"]),
    "ship_overrides_negative_mass": ([("ship_file: harbour_tug.yaml", "ship_file: harbour_tug.yaml\n"
                                       "    ship_overrides: {hull: {mass: -1.0}}")], {},
                                     ["vessels[0].ship_file", "hull.mass", "ship_overrides"]),
    # --- rope files
    "rope_file_missing": ([("rope_file: table1.yaml", "rope_file: no_such_rope.yaml")], {},
                          ["ropes[0].rope_file", "not found"]),
    "rope_file_empty": ([("table1.yaml", "bad_rope.yaml")], {"bad_rope.yaml": ""},
                        ["ropes[0].rope_file", "bad_rope.yaml"]),
    "rope_ea_1e15": ([("table1.yaml", "bad_rope.yaml")],
                     {"bad_rope.yaml": _rope("table1.yaml", ("axial_stiffness: null", "axial_stiffness: 1.0e+15"))},
                     ["ropes[0].rope_file", "bad_rope.yaml", "axial_stiffness"]),
    "rope_invalid_yaml": ([("table1.yaml", "bad_rope.yaml")],
                          {"bad_rope.yaml": _rope("table1.yaml", ("length: 100.0", "length: [100.0"))},
                          ["ropes[0].rope_file", "bad_rope.yaml", "not valid YAML", "line"]),
    "rope_duplicate_key": ([("table1.yaml", "bad_rope.yaml")],
                           {"bad_rope.yaml": _rope("table1.yaml", ("length: 100.0", "length: 100.0\nlength: 10.0"))},
                           ["ropes[0].rope_file", "bad_rope.yaml", "duplicate key 'length'"]),
    "rope_zero_length": ([("table1.yaml", "bad_rope.yaml")],
                         {"bad_rope.yaml": _rope("table1.yaml", ("length: 100.0", "length: 0.0"))},
                         ["ropes[0].rope_file", "bad_rope.yaml", "length"]),
    "rope_nan_diameter": ([("table1.yaml", "bad_rope.yaml")],
                          {"bad_rope.yaml": _rope("table1.yaml", ("diameter: 0.05", "diameter: .nan"))},
                          ["ropes[0].rope_file", "bad_rope.yaml", "diameter"]),
    # --- ropes in the scenario
    "deployed_longer_than_rope": ([("deployed_length: 60.0", "deployed_length: 190.0")], {},
                                  ["ropes[0].deployed_length", "longer than the rope"]),
    "deployed_zero": ([("deployed_length: 60.0", "deployed_length: 0.0")], {}, ["ropes[0].deployed_length"]),
    "deployed_on_straight_layout": ([("layout: winch", "layout: straight")], {}, ["ropes[0].deployed_length"]),
    "n_elements_5000": ([("deployed_length: 60.0", "deployed_length: 60.0\n    n_elements: 5000")], {},
                        ["ropes[0].n_elements"]),
    "end_unknown_attachment": ([("end_b: barge/bow_bollard", "end_b: barge/mast_top")], {},
                               ["ropes[0].end_b", "no attachment 'mast_top'"]),
    "end_unknown_vessel": ([("end_b: barge/bow_bollard", "end_b: ghost/bow_bollard")], {},
                           ["ropes[0].end_b", "'ghost'"]),
    "end_malformed": ([("end_a: tug/winch_aft", "end_a: tug")], {}, ["ropes[0].end_a"]),
    "fixed_end_without_position": ([("end_b: barge/bow_bollard", "end_b: fixed")], {}, ["ropes[0].end_b_position"]),
    "straight_rope_ends_coincide": ([("end_a: tug/winch_aft", "end_a: fixed\n    end_a_position: [1.0, 2.0, 0.0]"),
                                     ("end_b: barge/bow_bollard", "end_b: fixed\n    end_b_position: [1.0, 2.0, 0.0]"),
                                     ("layout: winch\n    deployed_length: 60.0\n", "layout: straight\n"),
                                     ("  - {time: 0.5, rope: towline, payout_rate: 0.5}\n", "")], {},
                                    ["ropes[0].end_b", "distinct"]),
    "fd_cable_between_two_vessels": ([("rope_file: table1.yaml", "rope_file: cable_001.yaml")], {},
                                     ["ropes[0].end_b", "fd_cable"]),
    # --- autopilots
    "autopilot_executable_unknown": ([("    vessel: tug\n    params", "    vessel: tug\n    executable: autopilott\n"
                                       "    params")], {}, ["autopilots[0].executable", "autopilott"]),
    "autopilot_package_unknown": ([("    vessel: tug\n    params", "    vessel: tug\n    package: no_such_pkg\n"
                                    "    params")], {}, ["autopilots[0].executable", "no_such_pkg"]),
    "autopilot_heading_400": ([("heading: 90.0,", "heading: 400.0,")], {}, ["autopilots[0].params.heading"]),
    "autopilot_param_unknown": ([("speed: 2.0}", "speeed: 2.0}")], {}, ["autopilots[0].params.speeed"]),
    "autopilot_param_type": ([("speed_control: true", "speed_control: yes please")], {},
                             ["autopilots[0].params.speed_control"]),
    "autopilot_track_without_waypoints": ([("mode: heading", "mode: track")], {}, ["autopilots[0].params", "track"]),
    "autopilot_engine_limits_crossed": ([("speed: 2.0}", "speed: 2.0, min_engine_order: 0.5, max_engine_order: 0.2}")],
                                        {}, ["autopilots[0].params", "engine limits"]),
    "autopilot_vessel_unknown": ([("    vessel: tug\n    params", "    vessel: ghost\n    params")], {},
                                 ["autopilots[0].vessel"]),
    # --- events and names
    "event_after_the_end": ([("{time: 1.0, vessel: barge", "{time: 50.0, vessel: barge")], {}, ["events[1].time"]),
    "event_unknown_rope": ([("rope: towline, payout_rate", "rope: ghostline, payout_rate")], {}, ["events[0].rope"]),
    "event_payout_nan": ([("payout_rate: 0.5", "payout_rate: .nan")], {}, ["events[0].payout_rate"]),
    "event_orders_autopiloted_vessel": ([("{time: 1.0, vessel: barge, anchor: heave_up}",
                                          "{time: 1.0, vessel: tug, engine_order: 0.5}")], {}, ["events[1].vessel"]),
    "event_time_and_trigger": ([("{time: 1.0, vessel: barge", "{time: 1.0, when: {vessel: barge, speed_below: 1.0}, "
                                 "vessel: barge")], {}, ["events[1]", "'time'", "'when'"]),
    "trigger_two_conditions": ([("{time: 1.0, vessel: barge", "{when: {vessel: barge, speed_below: 1.0, "
                                 "surge_below: 0.0}, vessel: barge")], {}, ["events[1]", "exactly one"]),
    "trigger_no_condition": ([("{time: 1.0, vessel: barge", "{when: {vessel: barge}, vessel: barge")], {},
                             ["events[1]", "exactly one"]),
    "trigger_vessel_unknown": ([("{time: 1.0, vessel: barge", "{when: {vessel: ghost, speed_below: 1.0}, "
                                 "vessel: barge")], {}, ["events[1].when.vessel", "'ghost'"]),
    "trigger_heading_change_zero": ([("{time: 1.0, vessel: barge", "{when: {vessel: barge, heading_change_deg: 0.0}, "
                                      "vessel: barge")], {}, ["events[1]", "heading_change_deg"]),
    "trigger_since_without_heading": ([("{time: 1.0, vessel: barge", "{when: {vessel: barge, speed_below: 1.0, "
                                        "since: 1.0}, vessel: barge")], {}, ["events[1]", "since"]),
    # --- contacts (hull_contact)
    "contact_fender_attachment_unknown": ([("events:\n", "contacts:\n  - {name: push, fender: tug/nose, hull: barge}\n"
                                            "events:\n")], {}, ["contacts[0].fender", "'nose'"]),
    "contact_hull_vessel_unknown": ([("events:\n", "contacts:\n  - {name: push, fender: tug/bow_bollard, hull: ghost}\n"
                                      "events:\n")], {}, ["contacts[0].hull", "'ghost'"]),
    "contact_on_its_own_hull": ([("events:\n", "contacts:\n  - {name: push, fender: tug/bow_bollard, hull: tug}\n"
                                  "events:\n")], {}, ["contacts[0].hull"]),
    "contact_stiffness_nan": ([("events:\n", "contacts:\n  - {name: push, fender: tug/bow_bollard, hull: barge, "
                                "stiffness: .nan}\nevents:\n")], {}, ["contacts[0].stiffness"]),
    "contact_fender_starts_inside_the_hull": ([("initial: {x: -80.0, y: 5.0", "initial: {x: -20.0, y: 5.0"),
                                               ("events:\n", "contacts:\n  - {name: push, fender: tug/stern_bollard, "
                                                "hull: barge}\nevents:\n")], {}, ["contacts[0]", "inside the hull"]),
    "contact_name_clashes_with_a_rope": ([("events:\n", "contacts:\n  - {name: towline, fender: tug/bow_bollard, "
                                           "hull: barge}\nevents:\n")], {}, ["towline", "namespaces must differ"]),
    "duplicate_vessel_names": ([("  - name: barge", "  - name: tug")], {}, ["'vessels'", "duplicate"]),
    "scenario_name_is_a_path": ([("name: malformed_base", "name: ../../escape")], {}, ["'name'"]),
    # --- issue 30 item 5: a contact the exchange cannot carry threw the pusher off (exit 0) or was
    # blamed on a rope
    "contact_stiffness_1e10": ([("events:\n", "contacts:\n  - {name: push, fender: tug/bow_bollard, hull: barge, "
                                 "stiffness: 1.0e+10}\nevents:\n")], {},
                               ["contacts[0].stiffness", "1e+10 N/m", "omega h < 0.5", "no damping allows more than"]),
    "contact_damping_1e10": ([("events:\n", "contacts:\n  - {name: push, fender: tug/bow_bollard, hull: barge, "
                               "damping: 1.0e+10}\nevents:\n")], {},
                             ["contacts[0].damping", "1e+10 N s/m", "must be below"]),
    "contact_damping_zero": ([("events:\n", "contacts:\n  - {name: push, fender: tug/bow_bollard, hull: barge, "
                               "damping: 0.0}\nevents:\n")], {}, ["contacts[0].damping", "at least"]),
    # --- issue 30 item 6: a straight layout laid the whole rope between ends far closer
    "straight_layout_ends_much_closer_than_the_rope": ([("layout: winch\n    deployed_length: 60.0\n", "layout: straight\n"),
                                                        ("  - {time: 0.5, rope: towline, payout_rate: 0.5}\n", "")], {},
                                                       ["ropes[0].layout", "100 m long", "deployed_length",
                                                        "layout: slack", "allow_slack: true"]),
    "straight_layout_past_the_breaking_load": ([("layout: winch\n    deployed_length: 60.0\n", "layout: straight\n"),
                                                ("  - {time: 0.5, rope: towline, payout_rate: 0.5}\n", ""),
                                                ("initial: {x: -80.0,", "initial: {x: -150.0,")], {},
                                               ["ropes[0].layout", "breaking load", "part at t = 0"]),
    "allow_slack_on_a_winch_layout": ([("deployed_length: 60.0", "deployed_length: 60.0\n    allow_slack: true")], {},
                                      ["ropes[0].allow_slack", "only for layout straight"]),
    # --- issue 30 item 6: orders to a vessel on a prescribed motion were ignored without a word
    "order_to_a_prescribed_motion_vessel": ([("initial: {x: -80.0, y: 5.0, heading_deg: 10.0, speed: 0.0}",
                                              "initial: {x: -80.0, y: 5.0, heading_deg: 10.0}\n"
                                              "    motion: {type: constant_speed, speed: 0.0}")], {},
                                            ["events[1].vessel", "prescribed motion (constant_speed)"]),
    # --- issue 30 item 5: nmea_out died of it mid-run (OverflowError), the run ended 0
    "nmea_utc_start_runs_past_year_9999": ([("events:\n", "nmea: {outputs: [{vessel: tug}], utc_start: '9999-12-31T23:59:59.99Z'}\nevents:\n")],
                                           {}, ["nmea.utc_start", "year 9999"]),
}


def _write(tmp_path, case):
    edits, files, _ = CASES[case]
    text = BASE
    for old, new in edits:
        assert old in text, f"{case}: edit target {old!r} not in the base scenario"
        text = text.replace(old, new, 1)
    for name, spec in files.items():
        if isinstance(spec, str):
            body = spec
        else:
            kind, src, file_edits = spec
            body = open(os.path.join(SHIPS if kind == "ship" else ROPES, src)).read()
            for old, new in file_edits:
                assert old in body, f"{case}: edit target {old!r} not in {src}"
                body = body.replace(old, new, 1)
        (tmp_path / name).write_text(body)
    path = tmp_path / "bad_scenario.yaml"
    path.write_text(text)
    return path


def test_corpus_is_large_enough():
    assert len(CASES) >= 40


def test_base_scenario_is_valid(tmp_path):
    """Each case fails for its own edit: the base itself passes every check."""
    from scenario_format.scenario import load_scenario
    path = tmp_path / "base.yaml"
    path.write_text(BASE)
    sc = load_scenario(str(path))
    assert [v.name for v in sc.vessels] == ["tug", "barge"] and sc.steps == 100


def _assert_refused(case, path, logs, proc):
    out = proc.stdout + proc.stderr
    assert proc.returncode == 2, out
    assert "Traceback" not in out, out
    assert str(path) in proc.stderr, out  # names the file
    for text in CASES[case][2]:
        assert text in proc.stderr, f"expected {text!r} in:\n{proc.stderr}"
    assert not logs.exists(), "a node was started"   # (not judged by wall time: a shared machine)


def _args(path, logs):
    return [str(path), "--no-record", "--quiet", "--log-dir", str(logs)]


@pytest.mark.timeout(120)
@pytest.mark.parametrize("case", sorted(CASES))
def test_malformed_input_refused_before_any_node_starts(case, tmp_path, run_in_process):
    path = _write(tmp_path, case)
    logs = tmp_path / "node_logs"
    proc = run_in_process("run_scenario", *_args(path, logs))
    _assert_refused(case, path, logs, proc)


@pytest.mark.timeout(120)
def test_malformed_input_refused_by_the_executable(tmp_path):
    """The same refusal through the installed executable, a process of its own (one case: a
    ship file the scenario names, refused for its hull mass)."""
    case = "ship_mass_1e30"
    path = _write(tmp_path, case)
    logs = tmp_path / "node_logs"
    proc = subprocess.run([executable_path("scenario_runner", "run_scenario"), *_args(path, logs)],
                          capture_output=True, text=True, timeout=110)
    _assert_refused(case, path, logs, proc)
