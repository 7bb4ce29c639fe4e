"""Issue 6: every scenario of the library runs to completion (shortened) and is recorded; bad
scenarios fail before any node starts, naming the problem."""
import glob
import os
import subprocess

import pytest

from conftest import executable_path

pytestmark = [pytest.mark.ros]


def _library():
    from ament_index_python.packages import get_package_share_directory
    return sorted(glob.glob(os.path.join(get_package_share_directory("scenario_runner"), "scenarios", "*.yaml")))


def run_scenario(*args, timeout=240):
    return subprocess.run([executable_path("scenario_runner", "run_scenario"), *args, "--quiet"],
                          capture_output=True, text=True, timeout=timeout)


def test_library_has_every_paper_case():
    names = {os.path.basename(p)[:-5] for p in _library()}
    expected = {"default_demo", "seed000_free_fall_air", "seed000_free_fall_water", "seed000_straight_tow_5kn",
                "seed000_sinusoidal_sway", "seed000_acceleration", "seed000_winch_payout",
                "seed002_barge_turn_gamma10", "seed002_barge_turn_gamma20", "seed002_barge_turn_gamma30",
                "seed002_barge_turn_gammam50", "seed003_s175_turn_35deg", "seed003_anchor_straight_6kn",
                "seed003_anchor_engine_stop", "seed003_anchor_turn_let_go", "seed003_anchor_turn_dredged",
                "seed004_acceleration", "seed004_deceleration_backing", "seed004_turn", "seed004_zigzag"}
    assert expected <= names


@pytest.mark.timeout(300)
@pytest.mark.parametrize("path", _library(), ids=lambda p: os.path.basename(p)[:-5])
def test_scenario_runs_to_completion(path, ros_domain, tmp_path):
    from mcap.reader import make_reader
    out = tmp_path / "run.mcap"
    proc = run_scenario(path, "--duration", "3", "--output", str(out))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "simulated" in proc.stdout
    with open(out, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary.statistics.message_count > 0


def _bad(tmp_path, text):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    return run_scenario(str(path), "--output", str(tmp_path / "x.mcap"), timeout=60)


GOOD = """name: t
duration: 1.0
vessels:
  - name: tug
    ship_file: harbour_tug.yaml
ropes:
  - name: line
    end_a: tug/towing_hook
    end_b: fixed
    end_b_position: [-50.0, 0.0, 0.0]
"""


@pytest.mark.timeout(60)
@pytest.mark.parametrize("old, new, message", [
    ("duration: 1.0", "duraton: 1.0", "key 'duraton': unknown key"),
    ("ship_file: harbour_tug.yaml", "ship_file: no_such_tug.yaml", "key 'vessels[0].ship_file': ship file"),
    ("end_a: tug/towing_hook", "end_a: tug/mast_top", "key 'ropes[0].end_a': vessel 'tug' has no attachment"),
    ("end_a: tug/towing_hook", "end_a: barge/bow_bollard", "vessel 'barge' is not in 'vessels'"),
])
def test_bad_scenario_fails_before_any_node_starts(tmp_path, old, new, message):
    proc = _bad(tmp_path, GOOD.replace(old, new))
    assert proc.returncode == 2
    assert "bad.yaml" in proc.stderr and message in proc.stderr, proc.stderr
    assert not (tmp_path / "x.mcap").exists()  # nothing started, nothing recorded
