"""benchmarks/bench_interaction.py, without timing anything: the fleet scenario it generates passes
the scenario check (six vessels, the 15 pairs between them, none starting inside another) and its
ROS-free part runs (docs/benchmarks.md shows its command; timings are never asserted)."""
import importlib.util
import itertools
import os
import subprocess
import sys

import yaml

from scenario_format.scenario import load_scenario

BENCH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "benchmarks", "bench_interaction.py")


def _bench():
    spec = importlib.util.spec_from_file_location("bench_interaction", BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_fleet_scenario_passes_the_scenario_check(tmp_path):
    bench = _bench()
    for with_pairs in (False, True):
        path = tmp_path / f"fleet_{with_pairs}.yaml"
        path.write_text(yaml.safe_dump(bench.fleet_scenario(f"fleet_{with_pairs}", with_pairs, 20.0, 20.0)))
        sc = load_scenario(str(path))
        assert len(sc.vessels) == 6
        names = [v.name for v in sc.vessels]
        assert [tuple(i.between) for i in sc.interactions] == (list(itertools.combinations(names, 2))
                                                               if with_pairs else [])


def test_the_model_part_runs():
    out = subprocess.run([sys.executable, BENCH, "--model-only"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "the 15 pairs' interaction (30 Wang loads, deep water)" in out.stdout
