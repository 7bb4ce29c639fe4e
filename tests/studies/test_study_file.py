"""Study files (no ROS): what a study plans from its file, and a bad file refused with exit
status 2 naming the file and the key before anything runs (the `study` command's own main(),
in this process)."""
import math

import pytest

from studies import study
from studies.study_file import get_value, parse_path, plan_study, set_value

GOOD = """
name: t
scenario: tow_head_seas.yaml
duration: 30.0
axes:
  - key: ropes[towline].deployed_length
    values: [90.0, 95.0]
  - key: events[5].engine_order
    range: {start: 0.3, stop: 0.5, step: 0.1}
seeds: {key: environment.waves.seed, count: 2, first: 5}
measures:
  peak: ropes.towline.tension_a_max
"""


def _write(tmp_path, text, name="study.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def _refused(tmp_path, capsys, text):
    path = _write(tmp_path, text)
    status = study.main([path, "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2, err
    assert path in err
    assert not (tmp_path / "out").exists(), "refused before anything ran or was written"
    return err


def test_a_study_plans_the_grid_of_its_axes_times_its_seeds(tmp_path):
    plan = plan_study(_write(tmp_path, GOOD), str(tmp_path / "scratch"))
    assert len(plan.runs) == 2 * 3 * 2
    assert len({r.run for r in plan.runs}) == 12
    first, last = plan.runs[0], plan.runs[-1]
    assert first.values == {"ropes[towline].deployed_length": 90.0, "events[5].engine_order": 0.3,
                            "environment.waves.seed": 5}
    assert last.values == {"ropes[towline].deployed_length": 95.0, "events[5].engine_order": 0.5,
                           "environment.waves.seed": 6}
    assert (last.configuration, last.sample) == (5, 1)
    sc = last.scenario
    assert sc["ropes"][0]["deployed_length"] == 95.0 and sc["events"][5]["engine_order"] == 0.5
    assert sc["environment"]["waves"]["seed"] == 6 and sc["environment"]["waves"]["hs"] == 2.0
    assert sc["duration"] == 420.0  # the scenario's: run_scenario --duration 30 shortens the runs
    assert sc["vessels"][0]["ship_file"] == "harbour_tug.yaml"  # in the package data: found from anywhere
    assert plan.run_duration == 30.0


def test_dotted_paths():
    assert parse_path("ropes[towline].end_a") == ["ropes", ("towline",), "end_a"]
    data = {"ropes": [{"name": "a", "x": 1}, {"name": "b"}], "events": [{"t": 0}]}
    set_value(data, "ropes[b].x", 2.0)
    set_value(data, "events[0].t", 5)
    set_value(data, "environment.wind.speed_kn", 20.0)
    assert data["ropes"][1]["x"] == 2.0 and data["events"][0]["t"] == 5
    assert data["environment"] == {"wind": {"speed_kn": 20.0}}
    assert get_value(data, "ropes[a].x") == 1
    with pytest.raises(KeyError):
        get_value(data, "ropes[c].x")
    with pytest.raises(ValueError, match="no item named 'c'"):
        set_value(data, "ropes[c].x", 1.0)


def test_ranges_and_random_draws(tmp_path):
    text = GOOD.replace("range: {start: 0.3, stop: 0.5, step: 0.1}", "range: {start: 0.3, stop: 0.5, num: 5}")
    text = text.replace("values: [90.0, 95.0]", "random: {distribution: uniform, low: 90.0, high: 100.0, "
                                                  "count: 3, seed: 4}")
    plan = plan_study(_write(tmp_path, text), str(tmp_path / "scratch"))
    import numpy as np
    lengths = sorted({r.values["ropes[towline].deployed_length"] for r in plan.runs})
    assert lengths == sorted(np.random.default_rng(4).uniform(90.0, 100.0, 3).tolist())
    orders = sorted({r.values["events[5].engine_order"] for r in plan.runs})
    assert orders == pytest.approx([0.3, 0.35, 0.4, 0.45, 0.5])


def test_unknown_key_is_refused(tmp_path, capsys):
    err = _refused(tmp_path, capsys, GOOD.replace("duration: 30.0", "duraton: 30.0"))
    assert "key 'duraton': unknown key" in err


def test_axis_over_a_value_the_scenario_does_not_have_is_refused(tmp_path, capsys):
    err = _refused(tmp_path, capsys, GOOD.replace("ropes[towline].deployed_length", "ropes[towline].lenght"))
    assert "key 'axes[0].key': 'ropes[towline].lenght'" in err and "lenght" in err and "unknown key" in err
    err = _refused(tmp_path, capsys, GOOD.replace("ropes[towline].deployed_length", "ropes[tow].deployed_length"))
    assert "key 'axes[0].key'" in err and "no item named 'tow'" in err
    err = _refused(tmp_path, capsys, GOOD.replace("events[5]", "events[99]"))
    assert "key 'axes[1].key'" in err and "no [99]" in err


def test_a_value_out_of_the_scenarios_range_is_refused(tmp_path, capsys):
    err = _refused(tmp_path, capsys, GOOD.replace("stop: 0.5, step: 0.1", "stop: 1.5, step: 0.6"))
    assert "key 'axes[1].key': 'events[5].engine_order' = 1.5" in err and "less than or equal to 1" in err


def test_empty_range_is_refused(tmp_path, capsys):
    err = _refused(tmp_path, capsys, GOOD.replace("start: 0.3, stop: 0.5", "start: 0.5, stop: 0.3"))
    assert "key 'axes[1].range': empty" in err
    err = _refused(tmp_path, capsys, GOOD.replace("values: [90.0, 95.0]", "values: []"))
    assert "key 'axes[0].values': empty" in err


def test_measures_are_checked_against_the_scenario(tmp_path, capsys):
    err = _refused(tmp_path, capsys, GOOD.replace("ropes.towline.tension_a_max", "ropes.hawser.tension_a_max"))
    assert "key 'measures.peak'" in err and "no rope 'hawser'" in err
    err = _refused(tmp_path, capsys, GOOD.replace("ropes.towline.tension_a_max", "tension_a_max"))
    assert "key 'measures.peak'" in err
    err = _refused(tmp_path, capsys, GOOD + "extremes: {measure: pk, duration: 10800.0}\n")
    assert "key 'extremes.measure': 'pk' is not one of the measures" in err


def test_missing_scenario_and_file_are_refused(tmp_path, capsys):
    err = _refused(tmp_path, capsys, GOOD.replace("tow_head_seas.yaml", "no_such_scenario.yaml"))
    assert "key 'scenario'" in err and "no_such_scenario.yaml" in err
    assert study.main([str(tmp_path / "none.yaml")]) == 2
    assert "not found" in capsys.readouterr().err


def test_missing_measure_in_a_summary_is_nan():
    from studies.one_run import measures_of
    got = measures_of({"ropes": {"towline": {"tension_a_max": 5.0, "broken": True}}},
                      {"a": "ropes.towline.tension_a_max", "b": "ropes.towline.turn", "c": "ropes.towline.broken"})
    assert got["a"] == 5.0 and math.isnan(got["b"]) and got["c"] == 1.0
