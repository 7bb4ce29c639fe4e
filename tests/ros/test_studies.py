"""Studies on Dask (issue 35): a 6-run study on a LocalCluster of 2 workers gives the same table as
the same runs made one by one with run_scenario and analyze (their command lines, equal values);
run again it runs nothing (resumed from its table); a run that fails is a row with its exit status
and message, and the study goes on to the end (exit status 1)."""
import json
import math
import os
import subprocess

import pandas as pd
import pytest

from conftest import executable_path, record_scenario

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

DURATION = 3.0
STUDY = f"""
name: acceptance
scenario: default_demo.yaml
duration: {DURATION}
axes:
  - key: ropes[towline].deployed_length
    values: [90.0, 95.0]
  - key: events[0].engine_order
    values: [0.05, 0.3, 0.6]
measures:
  peak_tension: ropes.towline.tension_a_max
  mean_tension: ropes.towline.tension_a_mean
  tug_speed_end: vessels.tug.speed_end
  barge_distance: vessels.barge.distance_run
"""


@pytest.fixture(scope="module")
def study_run(tmp_path_factory):
    from studies.study import run_study
    folder = tmp_path_factory.mktemp("study")
    path = folder / "acceptance.yaml"
    path.write_text(STUDY)
    lines = []
    result = run_study(str(path), str(folder / "out"), workers=2, keep_recordings=True, say=lines.append,
                       progress=False)
    return path, folder, result, lines


def _one_by_one(scenario: dict, folder):
    """The run as a user makes it: run_scenario, then analyze, each its own command."""
    import yaml
    folder.mkdir()
    path = folder / "scenario.yaml"
    path.write_text(yaml.safe_dump(scenario, sort_keys=False))
    record_scenario(path, folder / "run.mcap", "--duration", str(DURATION))
    proc = subprocess.run([executable_path("recording", "analyze"), str(folder / "run.mcap"), "-o", str(folder / "a"),
                           "--no-figures", "--quiet"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads((folder / "a" / "summary.json").read_text())


def test_study_table_equals_the_runs_made_one_by_one(study_run, ros_domain, tmp_path):
    _path, _folder, result, lines = study_run
    table = result.table
    assert len(table) == 6 and list(table["status"]) == ["ok"] * 6, table[["status", "message"]]
    assert any("dashboard http" in line for line in lines), lines
    assert pd.read_parquet(result.folder + "/results.parquet").equals(table)
    for row in table.itertuples():  # --keep-recordings: each run's recording beside the table
        assert row.recording == f"{result.folder}/runs/{row.run}/run.mcap" and os.path.getsize(row.recording) > 0
    measures = result.plan.study.measures
    for run in result.plan.runs:
        row = table[table["run"] == run.run].iloc[0]
        assert row["ropes[towline].deployed_length"] == run.values["ropes[towline].deployed_length"]
        summary = _one_by_one(run.scenario, tmp_path / run.run)
        for name, key in measures.items():
            entity, who, quantity = key.split(".")
            assert row[name] == summary[entity][who][quantity], (run.values, name)
    # the measures differ between the runs: the axes took effect
    assert table["peak_tension"].nunique() == 6
    stats = result.statistics
    assert len(stats) == 6 and stats["peak_tension_mean"].tolist() == table["peak_tension"].tolist()


def test_a_study_run_again_runs_nothing(study_run):
    from studies.study import run_study
    path, folder, first, _ = study_run
    again = run_study(str(path), str(folder / "out"), workers=2, say=lambda s: None, progress=False)
    assert again.ran == 0
    assert again.table.equals(first.table)


def test_failed_runs_are_recorded_and_the_study_goes_on(tmp_path, capsys):
    from studies.study import main
    path = tmp_path / "short.yaml"
    path.write_text(STUDY.replace("values: [0.05, 0.3, 0.6]", "values: [0.3]"))
    status = main([str(path), "-o", str(tmp_path / "out"), "--workers", "1", "--timeout", "0.5", "--quiet"])
    assert status == 1
    table = pd.read_parquet(tmp_path / "out" / "results.parquet")
    assert len(table) == 2 and list(table["status"]) == ["failed"] * 2
    assert list(table["exit_status"]) == [-1, -1]
    assert all("no end after 0.5 s" in m for m in table["message"])
    assert all(math.isnan(v) for v in table["peak_tension"])
    assert not (tmp_path / "out" / "runs").exists()  # without --keep-recordings nothing of the runs is left
    assert "failed run" in capsys.readouterr().out
