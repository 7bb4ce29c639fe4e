"""Placing a run's nodes in process groups (issue 34, --layout groups): whole tows together, the
load balanced, every node placed once, the scenario's order kept; and a node group process run
by hand refuses a file that is not one the runner wrote. In-process: no node starts."""
import pytest

from scenario_format.particulars import scenario_path
from scenario_format.scenario import load_scenario
from scenario_runner.node_processes import RUNNER_WEIGHT, _weight, node_groups
from scenario_runner.run_nodes import node_specs

pytestmark = pytest.mark.timeout(60)


def _specs(name):
    return node_specs(load_scenario(scenario_path(name)), scenario_path(name))


def test_every_node_once_in_scenario_order():
    specs = _specs("assist_s175_push_pull.yaml")
    for k in (1, 2, 3, 8):
        groups = node_groups(specs, k)
        assert len(groups) == k
        placed = [s.name for g in groups for s in g]
        assert sorted(placed) == sorted(s.name for s in specs)
        order = [s.name for s in specs]
        for g in groups:
            assert [s.name for s in g] == [n for n in order if n in {x.name for x in g}]
    assert node_groups(specs, 1) == [specs]   # one group: all in the runner's process


def test_tows_stay_whole_and_the_groups_balance(tmp_path):
    """Eight copies of the default tow over two groups: four whole tows each side, the runner's
    own share counted in the first (so it takes no more tows than the other)."""
    import yaml
    doc = yaml.safe_load(open(scenario_path("default_demo.yaml")))
    vessels, ropes = [], []
    for i in range(8):
        for v in doc["vessels"]:
            vessels.append({**v, "name": f"{v['name']}_{i}", "initial": {**v["initial"], "y": 300.0 * i}})
        for r in doc["ropes"]:
            ropes.append({**r, "name": f"{r['name']}_{i}",
                          "end_a": r["end_a"].replace("/", f"_{i}/", 1), "end_b": r["end_b"].replace("/", f"_{i}/", 1)})
    doc.update(vessels=vessels, ropes=ropes, events=[])
    path = tmp_path / "eight.yaml"
    path.write_text(yaml.safe_dump(doc))
    specs = node_specs(load_scenario(str(path)), str(path))
    groups = node_groups(specs, 2)
    tows = [{s.namespace.rsplit("_", 1)[-1] for s in g} for g in groups]
    assert len(tows[0]) == len(tows[1]) == 4 and not tows[0] & tows[1]
    for g in groups:   # a tow's three nodes (tug, barge, towline) in one group
        for i in {s.namespace.rsplit("_", 1)[-1] for s in g}:
            assert len([s for s in g if s.namespace.endswith(f"_{i}")]) == 3


def test_a_tow_bigger_than_a_share_is_split_node_by_node():
    specs = _specs("default_demo.yaml")   # one tow: heavier than half the work with the runner's
    groups = node_groups(specs, 2)
    assert all(groups)
    loads = [sum(_weight(s) for s in g) for g in groups]
    loads[0] += RUNNER_WEIGHT
    assert max(loads) - min(loads) <= max(_weight(s) for s in specs)


def test_node_group_refuses_a_file_it_cannot_read(tmp_path, capsys):
    from scenario_runner.node_group import main
    bad = tmp_path / "group.json"
    bad.write_text('[{"namespace": "/tug"}]')
    assert main([str(bad)]) == 2
    assert str(bad) in capsys.readouterr().err
    assert main([]) == 2


def test_the_default_count_is_one_process_while_the_run_fits_six_tenths_of_a_core():
    """(tows x 4.8 + 2) x 0.25 ms of work a step against 0.6 of the exchange period."""
    from scenario_runner.node_processes import default_group_count
    demo = _specs("default_demo.yaml")            # one tow: 6.8 units, 1.7 ms a step
    assert default_group_count(demo, 0.02, 2) == 1
    assert default_group_count(demo * 4, 0.02, 2) == 1       # 4 tows, 5.3 ms: a quarter of 20 ms
    assert default_group_count(demo * 8, 0.02, 2) == 1       # 8 tows, 10.1 ms: half, under 0.6
    assert default_group_count(demo * 10, 0.02, 2) == 2      # 10 tows, 12.6 ms: over 0.6 of 20 ms
    assert default_group_count(demo * 20, 0.02, 8) == 3      # 24.5 ms: 1.2 periods, 3 shares of 0.6
    assert default_group_count(demo * 20, 0.02, 2) == 2      # no more than the cores
