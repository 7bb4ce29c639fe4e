"""Who owns each order (scenario_runner/order_owner.py, ROS-free), the scenario key
`vessels[].manned` and run_scenario's --realtime / --lockstep, in-process (no nodes).

The rules (docs/scenarios.md, "Who gives the orders"): a scripted event sets only the controls it
names; an outside order takes the controls it changes and the script yields them until they are
handed back; a manned vessel is never ordered by the script."""
import math

import pytest
import yaml

from scenario_runner.order_owner import (ANCHOR_LET_GO, ANCHOR_NO_CHANGE, MANNED, OrderOwners, VesselOrder,
                                         WinchOrder)

pytestmark = pytest.mark.timeout(60)

H10 = math.radians(10.0)


def _owners(**kw):
    return OrderOwners({"tug": (0.5, 0.0), "barge": (0.0, 0.0)}, winches=["towline"], **kw)


def test_a_scripted_event_sets_only_what_it_names():
    o = _owners()
    # a person put the helm 10 deg to port (the engine as held)
    notes, _ = o.outside_vessel("tug", VesselOrder(0.5, H10), "/console", stamp_step=100)
    assert [(n.kind, n.control) for n in notes] == [("manual_order", "helm")]
    # an engine-only event: the engine changes, the helm stays the person's 10 deg port
    order, notes = o.script_vessel("tug", "events[1]", engine=0.8)
    assert (order.engine, order.helm, order.anchor) == (0.8, H10, ANCHOR_NO_CHANGE) and notes == []
    # without anybody at the helm: an engine-only event keeps the helm the script gave before
    o2 = _owners()
    o2.script_vessel("tug", "events[0]", helm=-H10)
    order, _ = o2.script_vessel("tug", "events[1]", engine=0.2)
    assert (order.engine, order.helm) == (0.2, -H10)


def test_an_outside_order_takes_the_controls_it_changes_and_the_script_yields():
    o = _owners()
    notes, confirm = o.outside_vessel("tug", VesselOrder(0.8, -H10), "/send_command", stamp_step=10)
    assert [(n.kind, n.target, n.control) for n in notes] == [("manual_order", "tug", "engine"),
                                                               ("manual_order", "tug", "helm")]
    assert "script yields" in notes[0].detail and "/send_command" in notes[0].detail
    assert "engine +0.80 (was +0.50)" in notes[0].detail and "helm 10.0 deg starboard" in notes[1].detail
    assert notes[0].value == 0.8 and notes[1].value == -H10
    assert not confirm  # the conductor sent the tug nothing since
    # the script's engine and helm orders yield, the anchor does not: the order carries the person's values
    order, notes = o.script_vessel("tug", "events[2]", engine=0.0, helm=0.0, anchor=ANCHOR_LET_GO)
    assert (order.engine, order.helm, order.anchor) == (0.8, -H10, ANCHOR_LET_GO)
    assert [(n.kind, n.control) for n in notes] == [("scripted_order_yielded", "engine"),
                                                    ("scripted_order_yielded", "helm")]
    assert "events[2]" in notes[0].detail and "manual control (/send_command)" in notes[0].detail
    # an event of only yielded controls sends nothing
    order, notes = o.script_vessel("tug", "events[3]", engine=0.3)
    assert order is None and len(notes) == 1
    # another vessel and the winch are still the script's
    order, notes = o.script_vessel("barge", "events[4]", helm=H10)
    assert order.helm == H10 and notes == []
    order, notes = o.script_winch("towline", "events[5]", 0.5)
    assert order == WinchOrder(0.5) and notes == []


def test_an_order_repeating_what_is_held_takes_nothing_and_a_second_person_is_named():
    o = _owners()
    notes, _ = o.outside_vessel("tug", VesselOrder(0.5, 0.0), "/autopilot", stamp_step=0)
    assert notes == []
    assert o.outside_vessel("tug", VesselOrder(0.6, 0.0), "/console", 1)[0][0].control == "engine"
    assert o.outside_vessel("tug", VesselOrder(0.7, 0.0), "/console", 2)[0] == []  # same person: said once
    notes, _ = o.outside_vessel("tug", VesselOrder(0.9, 0.0), "/live_view", 3)
    assert len(notes) == 1 and "taken over from /console" in notes[0].detail
    assert o.owner("tug", "engine") == "/live_view" and o.owner("tug", "helm") == "script"


def test_confirmation_when_the_script_ordered_the_vessel_since_the_outside_order_was_stamped():
    o = _owners()
    o.script_vessel("tug", "events[0]", engine=0.3)
    o.sent("tug", 50)
    # stamped 49, seen at step 51: the script's order of step 50 may have been applied after it
    _, confirm = o.outside_vessel("tug", VesselOrder(0.9, H10), "/console", stamp_step=49)
    assert confirm and o.confirmation("tug") == VesselOrder(0.9, H10)
    # the same person's next order, stamped after the script's last one: nothing to confirm
    notes, confirm = o.outside_vessel("tug", VesselOrder(0.1, H10), "/console", stamp_step=51)
    assert notes == [] and not confirm
    notes, confirm = o.outside_winch("towline", WinchOrder(0.0, 1, 0.0, 0.0, 9e4), "/console", stamp_step=0)
    assert notes[0].control == "winch" and "brake hold" in notes[0].detail and not confirm
    assert o.confirmation("towline") == WinchOrder(0.0, 1, 0.0, 0.0, 9e4)
    o.sent("towline", 7)
    assert o.outside_winch("towline", WinchOrder(0.1), "/console", stamp_step=6) == ([], True)


def test_hand_back():
    o = _owners()
    o.outside_vessel("tug", VesselOrder(0.8, -H10, ANCHOR_LET_GO), "/send_command", 0)
    assert {c for (t, c) in o.manual} == {"engine", "helm", "anchor"}
    notes = o.hand_back("tug", ["engine"], "/send_command")
    assert [(n.kind, n.control) for n in notes] == [("manual_handed_back", "engine")]
    assert "engine +0.80 holds until the script's next order" in notes[0].detail
    order, notes = o.script_vessel("tug", "events[3]", engine=0.1, helm=0.0)
    assert (order.engine, order.helm) == (0.1, -H10) and [n.control for n in notes] == ["helm"]
    notes = o.hand_back("tug", ["all"], "/x")
    assert sorted(n.control for n in notes) == ["anchor", "helm"] and {n.kind for n in notes} == {
        "manual_handed_back"}
    assert o.manual == {}
    assert [n.kind for n in o.hand_back("tug", ["helm"], "/x")] == ["hand_back_refused"]
    assert [n.kind for n in o.hand_back("tug", [], "/x")] == ["hand_back_refused"]


def test_a_manned_vessel_is_the_crews():
    o = _owners(manned=["barge"])
    assert all(o.owner("barge", c) == MANNED for c in ("engine", "helm", "anchor"))
    order, notes = o.script_vessel("barge", "events[0]", engine=0.5)
    assert order is None and notes[0].kind == "scripted_order_yielded"
    notes, confirm = o.outside_vessel("barge", VesselOrder(0.4, H10), "/console", 0)
    assert notes == [] and not confirm and o.held["barge"] == VesselOrder(0.4, H10)  # the crew's: not echoed
    assert [n.kind for n in o.hand_back("barge", ["all"], "/x")] == ["hand_back_refused"]
    with pytest.raises(ValueError, match="ship"):
        _owners(manned=["ship"])


# -- the scenario key ---------------------------------------------------------------------------

def _write(tmp_path, **changes):
    sc = {"name": "manned", "duration": 2.0, "mode": "lockstep",
          "vessels": [{"name": "tug", "ship_file": "harbour_tug.yaml"},
                      {"name": "barge", "ship_file": "box_barge_000.yaml", "initial": {"x": -60.0}}],
          "events": [{"time": 0.0, "vessel": "tug", "engine_order": 0.5}]}
    sc.update(changes)
    path = tmp_path / "manned.yaml"
    path.write_text(yaml.safe_dump(sc))
    return str(path)


def test_manned_key(tmp_path):
    from scenario_format.scenario import ScenarioError, load_scenario
    sc = load_scenario(_write(tmp_path))
    assert [v.manned for v in sc.vessels] == [False, False]
    vessels = [{"name": "tug", "ship_file": "harbour_tug.yaml", "manned": True},
               {"name": "barge", "ship_file": "box_barge_000.yaml", "initial": {"x": -60.0}}]
    with pytest.raises(ScenarioError) as err:
        load_scenario(_write(tmp_path, vessels=vessels))
    text = str(err.value)
    assert "key 'events[0].vessel'" in text and "vessels[0].manned" in text and "manned.yaml" in text
    sc = load_scenario(_write(tmp_path, vessels=vessels, events=[
        {"time": 1.0, "vessel": "barge", "steering_deg": 5.0},
        {"when": {"vessel": "tug", "speed_above": 1.0}, "vessel": "barge", "engine_order": 0.1}]))
    assert sc.vessels[0].manned
    with pytest.raises(ScenarioError, match=r"key 'vessels\[0\]\.manned'.*prescribed"):
        load_scenario(_write(tmp_path, events=[], vessels=[
            {"name": "tug", "ship_file": "harbour_tug.yaml", "manned": True,
             "motion": {"type": "constant_speed", "speed": 1.0}}]))
    with pytest.raises(ScenarioError, match=r"key 'vessels\[0\]\.manned'.*expected|Input should be a valid boolean"):
        load_scenario(_write(tmp_path, vessels=[{"name": "tug", "ship_file": "harbour_tug.yaml", "manned": "yes"}]))


# -- run_scenario --realtime / --lockstep ---------------------------------------------------------

@pytest.mark.parametrize("flag, mode", [([], "lockstep"), (["--realtime"], "realtime"), (["--lockstep"], "lockstep")])
def test_pace_overrides_the_scenarios_mode(tmp_path, flag, mode):
    from scenario_runner.run_scenario import build_parser, plan_run
    args = build_parser().parse_args([_write(tmp_path), "--no-record", "--log-dir", str(tmp_path / "logs"), *flag])
    plan, code = plan_run(args)
    assert code == 0 and plan.sc.mode == mode
    # the file says realtime: --lockstep overrides it the other way
    paced = _write(tmp_path, mode="realtime")
    args = build_parser().parse_args([paced, "--no-record", "--log-dir", str(tmp_path / "logs"), *flag])
    plan, _ = plan_run(args)
    assert plan.sc.mode == ("lockstep" if flag == ["--lockstep"] else "realtime")
    assert plan.sc.steps == 100 and plan.sc.vessels[1].initial.x == -60.0  # the rest as the file says


def test_realtime_and_lockstep_exclude_each_other(capsys):
    from scenario_runner.run_scenario import build_parser
    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args(["x.yaml", "--realtime", "--lockstep"])
    assert exc.value.code == 2 and "not allowed with argument" in capsys.readouterr().err
    assert "--realtime" in build_parser().format_help()


def test_send_command_hand_back_arguments(capsys):
    from scenario_runner.send_command import parse_args
    assert parse_args(["tug", "--hand-back"]).hand_back == "all"
    assert parse_args(["tug", "--hand-back", "engine, helm"]).hand_back == "engine,helm"
    assert parse_args(["tug", "--engine", "0.5"]).hand_back is None
    for bad in (["tug", "--hand-back", "rudder"], ["tug", "--hand-back", "engine", "--engine", "0.5"],
                ["tug", "--hand-back", ","]):
        with pytest.raises(SystemExit) as exc:
            parse_args(bad)
        assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "'rudder'" in err and "one or the other" in err
