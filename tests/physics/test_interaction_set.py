"""tug_dynamics.interaction_set: a run's pairs and banks in one compiled call equal the sum, per
vessel, of each pair's two HullPair.loads and each bank's BankEffect.loads_along (the
single-pair models of test_hull_interaction / test_bank_effect, with their own checks against
quadrature and closed forms), with the states carried on by hand; overlapping hulls switch their
pair off and nothing else."""
import itertools
import math

import numpy as np
import pytest

from tug_dynamics.bank_effect import BankEffect, BankPolyline
from tug_dynamics.hull_interaction import HullPair, SectionalAreaCurve, pair_from_ship_configs
from tug_dynamics.interaction_set import BankEntry, InteractionSet, PairEntry, PlanarState, WashEntry, propulsors_of
from tug_dynamics.ship_file import ship_config

SHIP = ship_config("s175_003.yaml")[1]
TUG = ship_config("harbour_tug.yaml")[1]


def _carried(s, lead):
    return s._replace(x=s.x + s.vx * lead, y=s.y + s.vy * lead)


def _by_hand(own, other, cfg_own, cfg_other, depth):
    c, s = math.cos(own.yaw), math.sin(own.yaw)
    dx, dy = other.x - own.x, other.y - own.y
    return np.array(pair_from_ship_configs(cfg_own, cfg_other).loads(c * dx + s * dy, -s * dx + c * dy,
                                                                      c * other.vx + s * other.vy, depth))


@pytest.mark.parametrize("depth", [math.inf, 20.0])
def test_six_vessels_fifteen_pairs_equal_the_single_pair_model_summed(depth):
    rng = np.random.default_rng(3)
    names = ["ship1", "ship2", "ship3", "tug1", "tug2", "tug3"]
    configs = {n: SHIP if n.startswith("ship") else TUG for n in names}
    hulls = {n: SectionalAreaCurve.from_ship_config(c) for n, c in configs.items()}
    # three lanes 60 m apart, ships and tugs 250 m apart, headings within 20 deg, speeds 0-4 m/s
    states = {n: PlanarState.from_body(250.0 * (i // 3) + rng.uniform(-20, 20), 60.0 * (i % 3),
                                       rng.uniform(-0.35, 0.35), rng.uniform(0, 4), rng.uniform(-0.3, 0.3))
              for i, n in enumerate(names)}
    pairs = [PairEntry(f"{a}_{b}", a, b) for a, b in itertools.combinations(names, 2)]
    lead = 0.075
    got, off = InteractionSet(hulls, pairs, depth=depth).loads(states, lead)
    carried = {n: _carried(s, lead) for n, s in states.items()}
    for n in names:
        expect = sum(_by_hand(carried[n], carried[m], configs[n], configs[m], depth) for m in names if m != n)
        np.testing.assert_allclose(got[n], expect, rtol=1e-12, atol=1e-9 * np.abs(expect).max(), err_msg=n)
    assert not any(off.values())


def test_a_bank_adds_its_suction_to_the_pair_loads_of_its_vessel():
    hulls = {"ship": SectionalAreaCurve.from_ship_config(SHIP), "tug": SectionalAreaCurve.from_ship_config(TUG)}
    bank = BankPolyline([[-500.0, -40.0], [2000.0, -40.0]])
    states = {"ship": PlanarState.from_body(0.0, 0.0, 0.0, 3.0, 0.0),
              "tug": PlanarState.from_body(75.0, 25.0, 0.05, 3.0, 0.1)}
    sets = InteractionSet(hulls, [PairEntry("bow", "tug", "ship")], [BankEntry("edge", "ship", bank)], depth=12.75)
    got, off = sets.loads(states, 0.15)
    c = {n: _carried(s, 0.15) for n, s in states.items()}
    y, n = BankEffect(hulls["ship"]).loads_along(bank, c["ship"].x, c["ship"].y, 0.0, 3.0, 12.75)
    pair_on_ship = _by_hand(c["ship"], c["tug"], SHIP, TUG, 12.75)
    np.testing.assert_allclose(got["ship"], pair_on_ship + [0.0, y, n], rtol=1e-12)
    np.testing.assert_allclose(got["tug"], _by_hand(c["tug"], c["ship"], TUG, SHIP, 12.75), rtol=1e-12)
    assert y < 0.0 and off == {"bow": False, "edge": False}      # drawn toward the bank, to starboard
    assert sets.vessels == ["tug", "ship"]


def test_a_sloped_bank_is_its_equivalent_walls_suction():
    """An entry with a slope: BankEffect.loads_along with the slope (the wall of the same d2b), a
    stronger pull than the vertical bank on the same line (the slope takes water from nearer the ship)."""
    hulls = {"ship": SectionalAreaCurve.from_ship_config(SHIP)}
    bank = BankPolyline([[-500.0, -60.0], [2000.0, -60.0]])
    states = {"ship": PlanarState.from_body(0.0, 0.0, 0.0, 3.0, 0.0)}
    sloped, _ = InteractionSet(hulls, [], [BankEntry("edge", "ship", bank, 3.0)], depth=12.75).loads(states, 0.15)
    vertical, _ = InteractionSet(hulls, [], [BankEntry("edge", "ship", bank)], depth=12.75).loads(states, 0.15)
    c = _carried(states["ship"], 0.15)
    y, n = BankEffect(hulls["ship"]).loads_along(bank, c.x, c.y, 0.0, 3.0, 12.75, slope=3.0)
    np.testing.assert_allclose(sloped["ship"], [0.0, y, n], rtol=1e-12)
    assert sloped["ship"][1] < vertical["ship"][1] < 0.0


def test_a_depth_fields_banks_are_bank_effects_loads_in_depth():
    """An entry without a line (BankEntry.bank None): BankEffect.loads_in_depth of the set's depth
    field at the carried state; without a depth field the set refuses it."""
    hulls = {"ship": SectionalAreaCurve.from_ship_config(SHIP)}

    def field(xs, ys):      # a 1:3 bank 60 m to starboard of y = 0
        return np.minimum(12.75, (np.asarray(ys, float) + 60.0) / 3.0)
    states = {"ship": PlanarState.from_body(0.0, 0.0, 0.1, 3.0, 0.2)}
    got, off = InteractionSet(hulls, [], [BankEntry("edge", "ship", None)], depth_field=field).loads(states, 0.15)
    c = _carried(states["ship"], 0.15)
    speed = math.cos(c.yaw) * c.vx + math.sin(c.yaw) * c.vy
    y, n = BankEffect(hulls["ship"]).loads_in_depth(field, c.x, c.y, c.yaw, speed)
    np.testing.assert_allclose(got["ship"], [0.0, y, n], rtol=1e-12)
    assert y < 0.0 and off == {"edge": False}
    with pytest.raises(ValueError, match="no depth_field given"):
        InteractionSet(hulls, [], [BankEntry("edge", "ship", None)])


def test_a_wash_adds_its_jets_to_the_pair_loads_of_its_target():
    """loads [wang, wash]: the ship feels the pair's Wang load plus the tug's jets (wash_load of the
    carried states); the tug only its Wang load; a step without the tug's thrust: no wash."""
    hulls = {"ship": SectionalAreaCurve.from_ship_config(SHIP), "tug": SectionalAreaCurve.from_ship_config(TUG)}
    states = {"ship": PlanarState.from_body(0.0, 0.0, 0.0, 0.2, 0.0),
              "tug": PlanarState.from_body(60.0, 50.0, math.radians(80.0), 0.5, 0.0)}
    kind, props = propulsors_of(TUG)
    assert kind == "propellers" and len(props) == 2
    wash = WashEntry("w", "tug", "ship")
    sets = InteractionSet(hulls, [PairEntry("p", "tug", "ship")], washes=[wash], propulsors={"tug": props},
                          drafts={"ship": SHIP["hull"]["draft"]})
    thrust = {"tug": [(60e3, 0.0), (60e3, 0.0)]}
    got, _ = sets.loads(states, 0.15, thrust)
    c = {n: _carried(s, 0.15) for n, s in states.items()}
    y, n = sets.wash_load(wash, c["tug"], c["ship"], thrust["tug"])
    assert y < -1e3 and n < 0.0          # the tug's jets on the port side, forward of midship: pushed to starboard
    np.testing.assert_allclose(got["ship"], _by_hand(c["ship"], c["tug"], SHIP, TUG, math.inf) + [0.0, y, n],
                               rtol=1e-12)
    np.testing.assert_allclose(got["tug"], _by_hand(c["tug"], c["ship"], TUG, SHIP, math.inf), rtol=1e-12)
    no_thrust, _ = sets.loads(states, 0.15)
    np.testing.assert_allclose(no_thrust["ship"], _by_hand(c["ship"], c["tug"], SHIP, TUG, math.inf), rtol=1e-12)
    # C_w scales the wash and nothing else (F = C_w T sin^2 psi x the intercepted fraction)
    half = InteractionSet(hulls, [PairEntry("p", "tug", "ship")], washes=[wash._replace(impingement=0.5)],
                          propulsors={"tug": props}, drafts={"ship": SHIP["hull"]["draft"]})
    got_half, _ = half.loads(states, 0.15, thrust)
    np.testing.assert_allclose(got_half["ship"], _by_hand(c["ship"], c["tug"], SHIP, TUG, math.inf)
                               + [0.0, 0.5 * y, 0.5 * n], rtol=1e-12)
    with pytest.raises(ValueError, match="impingement must be within"):
        InteractionSet(hulls, washes=[wash._replace(impingement=1.5)], propulsors={"tug": props},
                       drafts={"ship": 8.5})


def test_overlapping_hulls_switch_only_their_pair_off():
    hulls = {n: SectionalAreaCurve.from_ship_config(TUG) for n in ("a", "b", "c")}
    states = {"a": PlanarState.from_body(0.0, 0.0, 0.0, 2.0, 0.0), "b": PlanarState.from_body(5.0, 3.0, 0.0, 2.0, 0.0),
              "c": PlanarState.from_body(0.0, 40.0, 0.0, 2.0, 0.0)}
    pairs = [PairEntry("ab", "a", "b"), PairEntry("ac", "a", "c"), PairEntry("bc", "b", "c")]
    got, off = InteractionSet(hulls, pairs).loads(states, 0.0)
    assert off == {"ab": True, "ac": False, "bc": False}
    pair = HullPair(hulls["a"], hulls["a"])
    with pytest.raises(ValueError):        # the single-pair model refuses the same overlap
        pair.check(5.0, 3.0, 2.0, math.inf)
    np.testing.assert_allclose(got["a"], _by_hand(states["a"], states["c"], TUG, TUG, math.inf), rtol=1e-12)
    # a bank the ship is over switches it off
    bank = BankPolyline([[-100.0, 1.0], [100.0, 1.0]])
    _, off = InteractionSet(hulls, [], [BankEntry("quay", "a", bank)]).loads(states, 0.0)
    assert off == {"quay": True}


def test_bad_declarations_are_named():
    hulls = {"a": SectionalAreaCurve.from_ship_config(TUG)}
    with pytest.raises(ValueError, match="vessel 'b' has no hull"):
        InteractionSet(hulls, [PairEntry("ab", "a", "b")])
    with pytest.raises(ValueError, match="'a' twice"):
        InteractionSet(hulls, [PairEntry("aa", "a", "a")])
    hulls["b"] = hulls["a"]
    with pytest.raises(ValueError, match=r"names \['x'\] used twice"):
        InteractionSet(hulls, [PairEntry("x", "a", "b"), PairEntry("x", "b", "a")])
    with pytest.raises(ValueError, match="depth"):
        InteractionSet(hulls, [], depth=0.0)
