"""Issue 33 item 4 in a run: the tugs' propeller wash on the ship they work
(assist_s175_berth_turn_wash: the bow tug pulls north on a 56 m line with its jets straight back
at the S-175's port bow; the ASD tug pushes on the port quarter, its jets leaving the hull).

Truths: the interaction node's recorded wash on the ship equals tug_dynamics.propeller_wash at
the recorded positions of the step before (carried on to the middle of the step the load acts
over) and the recorded thrust of that step (bow tug: /bow_tug/status, its propellers' total shared
over its two; ASD tug: each unit's open-water thrust and azimuth from /stern_tug/thrusters), the
geometry (each propeller's place and jet heading in the ship's axes) done here by hand; momentum:
the wash never exceeds the jets' thrust; the wash points against the pull (it pushes the bow
away from the tug), so the ship swings less than in the same run without it; a run in one process
is identical; a wash from a vessel without propulsion exits 2 before start."""
import math

import numpy as np
import pytest
import yaml

from conftest import record_scenario, reserved_domain
from test_interaction_runs import _library, _states
from test_recording import decoded

pytestmark = [pytest.mark.ros, pytest.mark.timeout(600)]

DURATION, RATE = 30.0, 20.0
WASH = "/interactions/on_ship/wrench"
TOPICS = ["/ship/odom", "/bow_tug/odom", "/stern_tug/odom", "/bow_tug/status", "/stern_tug/thrusters", WASH]


def _physics(msgs):
    return {"ship": _states(msgs, "ship"), "bow_tug": _states(msgs, "bow_tug"),
            "stern_tug": _states(msgs, "stern_tug"),
            "bow_thrust": np.array([m.thrust for m in msgs["/bow_tug/status"]]),
            "stern_units": np.array([[list(m.open_water_thrust), list(m.azimuth)] for m in msgs["/stern_tug/thrusters"]]),
            "wash": np.array([[m.wrench.force.x, m.wrench.force.y, m.wrench.torque.z] for m in msgs[WASH]])}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("wash")
    out = {}
    with reserved_domain():
        for name, scenario, layout in (("wash", "assist_s175_berth_turn_wash.yaml", "processes"),
                                       ("wash_one_process", "assist_s175_berth_turn_wash.yaml", "one_process"),
                                       ("plain", "assist_s175_berth_turn.yaml", "processes")):
            record_scenario(scenario, base / f"{name}.mcap", "--duration", DURATION, layout=layout, timeout=400)
            topics = TOPICS if name != "plain" else TOPICS[:3]
            out[name] = _physics(decoded(base / f"{name}.mcap", topics)) if name != "plain" else {
                "ship": _states(decoded(base / f"{name}.mcap", topics), "ship")}
    return out


def _lever_by_dblquad(jet, side, offset, psi):
    """The intercepted flux's centroid u (from the foot): V^2 (and its surface mirror) over the side
    by scipy's dblquad, V from the jet's formula."""
    from scipy import integrate
    from tug_dynamics.propeller_wash import jet_velocity

    def density(z, u, weight):
        x = u * math.cos(psi) + offset * math.sin(psi)
        h2 = max(u * u + offset * offset - x * x, 0.0)
        return weight(u) * sum(jet_velocity(x, math.sqrt(h2 + (z - zp) ** 2), jet.v0, jet.d0) ** 2
                               for zp in (-jet.depth, jet.depth))
    total, first = (integrate.dblquad(density, side.u_start, side.u_end, -side.draft, 0.0, args=(w,),
                                      epsabs=0.0, epsrel=1e-8)[0] for w in (lambda u: 1.0, lambda u: u))
    return first / total


def _jets_by_hand(ship, tug, units, propellers, levers=False):
    """(F_y, N) on the ship: for each propeller (x, y, depth, D0) of the tug with (thrust, azimuth),
    its place and jet heading in the ship's axes, then PropellerJet.wash_force on the port or
    starboard side (HullSide from the foot, psi the jet's angle to that side); the moment's lever
    to the intercepted flux's centroid by dblquad (levers=True), else to the jet's foot."""
    from tug_dynamics.propeller_wash import HullSide, PropellerJet
    half_l, half_b, draft = 87.5, 12.7, 8.5
    fy = fn = 0.0
    for (px, py, depth, d0), (thrust, azimuth) in zip(propellers, units):
        if thrust == 0.0:
            continue
        wx = tug[0] + math.cos(tug[2]) * px - math.sin(tug[2]) * py - ship[0]
        wy = tug[1] + math.sin(tug[2]) * px + math.cos(tug[2]) * py - ship[1]
        bx = math.cos(ship[2]) * wx + math.sin(ship[2]) * wy
        by = -math.sin(ship[2]) * wx + math.cos(ship[2]) * wy
        heading = tug[2] + azimuth + (math.pi if thrust > 0 else 0.0) - ship[2]
        jx, jy = math.cos(heading), math.sin(heading)
        toward = -jy if by > 0 else jy                   # the jet's part toward the side it faces
        if abs(by) <= half_b or toward == 0.0:
            continue
        psi = math.asin(max(-1.0, min(1.0, toward)))
        along = 1.0 if jx >= 0 else -1.0
        u0, u1 = sorted((along * (-half_l - bx), along * (half_l - bx)))
        jet = PropellerJet(abs(thrust), d0, depth, ducted=True)     # D0 = D: both tugs' units are ducted
        side = HullSide(u0, u1, draft)
        f = jet.wash_force(side, abs(by) - half_b, psi)
        f_y = -math.copysign(f, by) * math.copysign(1.0, psi)      # away from the tug, or suction toward it
        fy += f_y
        if f != 0.0:
            fn += f_y * (bx + along * (_lever_by_dblquad(jet, side, abs(by) - half_b, psi) if levers else 0.0))
    return fy, fn


HARBOUR_TUG_PROPELLERS = [(-9.5, 2.1, 2.0, 2.0), (-9.5, -2.1, 2.0, 2.0)]   # harbour_tug.yaml
ASD_UNITS = [(-11.5, 3.0, 3.9, 2.4), (-11.5, -3.0, 3.9, 2.4)]                # asd_tug.yaml


def test_recorded_wash_is_the_jets_at_the_recorded_state(runs):
    r = runs["wash"]
    steps = int(DURATION * RATE)
    assert len(r["wash"]) == len(r["ship"]) == steps + 1
    for k in list(range(1, steps + 1, 7)) + [150, 300, 450, 600]:
        j = k - 1                       # the load stamped k comes from step k - 1, carried on 1.5 steps
        lead = 1.5 / RATE
        carried = {v: r[v][j] + np.array([r[v][j, 3] * lead, r[v][j, 4] * lead, 0.0, 0.0, 0.0])
                   for v in ("ship", "bow_tug", "stern_tug")}
        exact = k % 150 == 0
        bow = _jets_by_hand(carried["ship"], carried["bow_tug"], [(r["bow_thrust"][j] / 2, 0.0)] * 2,
                            HARBOUR_TUG_PROPELLERS, levers=exact)
        stern = _jets_by_hand(carried["ship"], carried["stern_tug"], list(zip(*r["stern_units"][j])), ASD_UNITS,
                              levers=exact)
        x, y, n = r["wash"][k]
        assert x == 0.0
        assert y == pytest.approx(bow[0] + stern[0], rel=1e-6, abs=1.0), k
        if exact:
            assert n == pytest.approx(bow[1] + stern[1], rel=1e-4, abs=10.0), k
        else:       # levers to the jets' feet here: the bow end cuts the footprint, within a few metres
            assert n == pytest.approx(bow[1] + stern[1], abs=5.0 * abs(y) + 10.0), k


def test_the_wash_opposes_the_pull_and_never_exceeds_the_thrust(runs):
    r = runs["wash"]
    wash_y, thrust = r["wash"][1:, 1], r["bow_thrust"][:-1]
    late = slice(len(wash_y) // 2, None)
    # the bow tug is to port (+y) pulling north: its wash pushes the bow to starboard (-y), turning it clockwise
    assert np.all(wash_y[late] < 0.0) and np.all(r["wash"][1:, 2][late] < 0.0)
    assert np.all(-wash_y <= thrust + 1e-6)
    # a 56 m line: most of the jets reach the hull (upper bound: an ideal plate, C_w = 1)
    assert 0.3 < float(np.mean(-wash_y[late] / thrust[late])) < 1.0


def test_the_ship_swings_less_with_the_wash(runs):
    """Counter-clockwise swing off the berth at 30 s: the wash takes part of the bow tug's pull."""
    swing_wash = runs["wash"]["ship"][-1, 2] - runs["wash"]["ship"][0, 2]
    swing_plain = runs["plain"]["ship"][-1, 2] - runs["plain"]["ship"][0, 2]
    assert 0.0 < swing_wash < 0.9 * swing_plain


def test_identical_in_one_process(runs):
    first, again = runs["wash"], runs["wash_one_process"]
    for key in first:
        np.testing.assert_array_equal(first[key], again[key], err_msg=key)


def test_a_wash_from_a_vessel_without_propulsion_exits_2_before_start(tmp_path, run_in_process):
    sc = yaml.safe_load(open(_library("assist_s175_berth_turn_wash.yaml")))
    sc["vessels"][1]["ship_file"] = "box_barge_000.yaml"
    sc["ropes"] = []
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(sc))
    proc = run_in_process("run_scenario", path, "--no-record", "--quiet")
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "key 'interactions[0].loads': wash of 'bow_tug' (box_barge_000.yaml): propeller wash: the vessel has " \
           "no propellers or azimuth thrusters" in proc.stderr, proc.stderr



def test_the_wash_entry_reaches_the_node_and_bad_entries_are_named(tmp_path, run_in_process):
    """wash_impingement is C_w of the node's washes entry; without 'wash' in its loads it exits 2;
    the node's parameter refuses a malformed entry or a C_w outside 0..1, naming it."""
    from hull_contact.interaction_node import parse_washes
    from scenario_format.scenario import load_scenario
    from scenario_runner.run_nodes import _interaction_specs
    sc = yaml.safe_load(open(_library("assist_s175_berth_turn_wash.yaml")))
    sc["interactions"][0]["wash_impingement"] = 0.6
    path = tmp_path / "half.yaml"
    path.write_text(yaml.safe_dump(sc))
    (spec,) = _interaction_specs(load_scenario(str(path)), str(path), "run")
    washes = spec.params["washes"]
    assert washes == ["bow_tug_ship_interaction_wash=bow_tug,ship,0.6", "stern_tug_ship_interaction_wash=stern_tug,ship,1.0"]
    assert [(w.source, w.target, w.impingement) for w in parse_washes(washes)] == [
        ("bow_tug", "ship", 0.6), ("stern_tug", "ship", 1.0)]
    assert parse_washes(["w=a,b"])[0].impingement == 1.0
    for bad in (["w=a,b,1.5"], ["w=a,b,x"], ["w=a"], ["w=a,b,0.5,1"], ["w=,b"]):
        with pytest.raises(ValueError, match="parameter washes: \"w\" needs"):
            parse_washes(bad)
    sc["interactions"][0]["loads"] = ["wang"]
    path.write_text(yaml.safe_dump(sc))
    proc = run_in_process("run_scenario", path, "--no-record", "--quiet")
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "key 'interactions[0].wash_impingement': only with 'wash' in its loads" in proc.stderr, proc.stderr
