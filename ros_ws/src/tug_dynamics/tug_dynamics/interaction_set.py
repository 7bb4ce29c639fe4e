"""A run's hull interactions together: every declared pair's Wang (1975) loads
(tug_dynamics.hull_interaction), every declared bank's image-method suction
(tug_dynamics.bank_effect) and every declared wash's jets on a hull (tug_dynamics.propeller_wash),
summed per vessel, from the vessels' planar states and propulsors' thrust. ROS-free; the
hull_contact interaction node is its shell (one node for all the run's interactions, issue 33's
speed goal: one node and one wrench per vessel, not a node and two wrenches per pair).

All the pairs are one compiled call (`_pair_loads`): each pair's two directed loads by the same
sums as `HullPair.loads` (the same Gauss nodes and closed-form inner integral, `wang_loads`),
with the states carried on, Wang's arguments and the overlap test done in the kernel.
"""
from __future__ import annotations

import math
from typing import Dict, List, NamedTuple, Optional, Sequence, Tuple

import numpy as np
from numba import njit

from tug_dynamics.bank_effect import BankEffect, BankPolyline
from tug_dynamics.hull_interaction import (DEFAULT_NODES, IMAGE_COUNT, SectionalAreaCurve, composite_gauss,
                                           wang_loads)
from tug_dynamics.propeller_wash import GAUSS_W, GAUSS_X, efflux_diameter, wash_on_hull

ZERO_LOADS = (0.0, 0.0, 0.0)


class PlanarState(NamedTuple):
    """A vessel's horizontal position, heading and velocity over ground (world, REP-103)."""
    x: float
    y: float
    yaw: float
    vx: float
    vy: float

    @staticmethod
    def from_body(x: float, y: float, yaw: float, u: float, v: float) -> "PlanarState":
        """From the position, heading and body-axis velocity (u forward, v to port) of odometry."""
        c, s = math.cos(yaw), math.sin(yaw)
        return PlanarState(x, y, yaw, c * u - s * v, s * u + c * v)


def ahead(state: PlanarState, seconds: float) -> PlanarState:
    """The state carried on at its velocity (heading and velocity held): where the vessel is in
    the middle of the step a load computed now acts over."""
    return state._replace(x=state.x + state.vx * seconds, y=state.y + state.vy * seconds)


def wang_arguments(own: PlanarState, other: PlanarState) -> Tuple[float, float, float]:
    """(stagger, separation, speed) of `other` seen from `own`: its midship ahead and to port in
    own's body axes, and its velocity over ground along own's x axis (Wang's parallel courses)."""
    c, s = math.cos(own.yaw), math.sin(own.yaw)
    dx, dy = other.x - own.x, other.y - own.y
    return c * dx + s * dy, -s * dx + c * dy, c * other.vx + s * other.vy


@njit(cache=True)
def _pair_loads(states, lead, pair_a, pair_b, hull_of, x1, sway_w1, yaw_w1, half_length, slope, length, beam,
                depth, images, rho, loads, off):
    """For every pair p of vessels (pair_a[p], pair_b[p]) (rows of `states`: x, y, yaw, vx, vy),
    carried on `lead` s: Wang's (X, Y, N) on each from the other added into `loads` (a row a
    vessel), unless their hulls overlap (off[p] = 1, both loads nil: HullPair.check's limit)."""
    loads[:, :] = 0.0
    for p in range(pair_a.shape[0]):
        a = pair_a[p]
        b = pair_b[p]
        ha = hull_of[a]
        hb = hull_of[b]
        xa = states[a, 0] + states[a, 3] * lead
        ya = states[a, 1] + states[a, 4] * lead
        xb = states[b, 0] + states[b, 3] * lead
        yb = states[b, 1] + states[b, 4] * lead
        dx = xb - xa
        dy = yb - ya
        ca = math.cos(states[a, 2])
        sa = math.sin(states[a, 2])
        cb = math.cos(states[b, 2])
        sb = math.sin(states[b, 2])
        stagger_ab = ca * dx + sa * dy            # b seen from a
        sep_ab = -sa * dx + ca * dy
        stagger_ba = -(cb * dx + sb * dy)         # a seen from b
        sep_ba = sb * dx - cb * dy
        reach = 0.5 * (length[ha] + length[hb])
        clear = 0.5 * (beam[ha] + beam[hb])
        if (abs(stagger_ab) < reach and abs(sep_ab) < clear) or (abs(stagger_ba) < reach and abs(sep_ba) < clear):
            off[p] = 1
            continue
        off[p] = 0
        speed_b = ca * states[b, 3] + sa * states[b, 4]   # b's velocity along a's axis
        speed_a = cb * states[a, 3] + sb * states[a, 4]
        fx, fy, fn = wang_loads(x1[ha], sway_w1[ha], yaw_w1[ha], half_length[hb], slope[hb], stagger_ab, sep_ab,
                                depth, images, rho[ha], speed_b)
        loads[a, 0] += fx
        loads[a, 1] += fy
        loads[a, 2] += fn
        fx, fy, fn = wang_loads(x1[hb], sway_w1[hb], yaw_w1[hb], half_length[ha], slope[ha], stagger_ba, sep_ba,
                                depth, images, rho[hb], speed_a)
        loads[b, 0] += fx
        loads[b, 1] += fy
        loads[b, 2] += fn


class PairEntry(NamedTuple):
    name: str
    a: str
    b: str


class BankEntry(NamedTuple):
    name: str
    vessel: str
    bank: Optional[BankPolyline]   # None: the banks of the set's depth_field, across the ship
    slope: float = 0.0      # m across per m down from the line (the waterline); 0: a vertical wall


class WashEntry(NamedTuple):
    """`source`'s propeller jets on `target`'s hull side (propeller_wash.wash_on_hull)."""
    name: str
    source: str
    target: str
    impingement: float = 1.0


class Propulsor(NamedTuple):
    """Where a propeller's or azimuth thruster's jet leaves it: body position (m), the depth of
    its axis below the waterline (m) and its efflux diameter D0 (m)."""
    x: float
    y: float
    depth: float
    d0: float


def propulsors_of(config: dict) -> Tuple[str, List[Propulsor]]:
    """("thrusters" or "propellers", the propulsors) of a ship file's mapping: its azimuth
    thrusters if it has any (each unit's thrust and azimuth are known), else its propellers (thrust
    along body x, the vessel's total shared equally). A vessel with both is refused: its status
    gives the propellers' thrust only summed with the thrusters'."""
    thrusters, propellers = config.get("thrusters") or [], config.get("propellers") or []
    if thrusters and propellers:
        raise ValueError("propeller wash: a vessel with both propellers and azimuth thrusters is not modelled")
    kind, units = ("thrusters", thrusters) if thrusters else ("propellers", propellers)
    if not units:
        raise ValueError("propeller wash: the vessel has no propellers or azimuth thrusters")
    return kind, [Propulsor(float(u["position"][0]), float(u["position"][1]), max(0.0, -float(u["position"][2])),
                            efflux_diameter(float(u["diameter"]), bool(u.get("ducted", False)))) for u in units]


class InteractionSet:
    """The run's pairs and banks over its vessels' hulls (Wang's parabolas), in water of `depth`
    (math.inf: deep; `depth_field(xs, ys)` the depths whose banks a bank entry without a line
    feels). `loads(states, lead)` gives each vessel's summed (X, Y, N) (body axes,
    about midship) and which entries are off (overlapping hulls, a ship at or over its bank).
    A wash needs its target's draft (`drafts`) and its source's `propulsors`; `loads` then takes
    each source's (thrust N signed, azimuth rad) per propulsor."""

    def __init__(self, hulls: Dict[str, SectionalAreaCurve], pairs: Sequence[PairEntry] = (),
                 banks: Sequence[BankEntry] = (), depth: float = math.inf,
                 water_density: Dict[str, float] = None, nodes: int = DEFAULT_NODES,
                 washes: Sequence[WashEntry] = (), propulsors: Dict[str, Sequence[Propulsor]] = None,
                 drafts: Dict[str, float] = None, depth_field=None):
        if math.isnan(depth) or depth <= 0.0:
            raise ValueError(f"interactions: depth must be > 0 (math.inf for deep water), got {depth!r}")
        density = {name: 1025.0 for name in hulls} | dict(water_density or {})
        names = []
        propulsors, drafts = dict(propulsors or {}), dict(drafts or {})
        for entry in washes:
            if entry.source == entry.target:
                raise ValueError(f"interaction '{entry.name}': '{entry.source}' washes its own hull")
            if not propulsors.get(entry.source):
                raise ValueError(f"interaction '{entry.name}': '{entry.source}' has no propulsors given")
            if not drafts.get(entry.target, 0.0) > 0.0:
                raise ValueError(f"interaction '{entry.name}': '{entry.target}' has no draft given")
            if not 0.0 <= entry.impingement <= 1.0:
                raise ValueError(f"interaction '{entry.name}': impingement must be within [0, 1], "
                                 f"got {entry.impingement!r}")
        for entry in list(pairs) + list(banks) + list(washes):
            felt = ((entry.a, entry.b) if isinstance(entry, PairEntry) else
                    (entry.target,) if isinstance(entry, WashEntry) else (entry.vessel,))
            for vessel in felt:
                if vessel not in hulls:
                    raise ValueError(f"interaction '{entry.name}': vessel '{vessel}' has no hull "
                                     f"(known: {sorted(hulls)})")
                if vessel not in names:
                    names.append(vessel)
            if isinstance(entry, PairEntry) and entry.a == entry.b:
                raise ValueError(f"interaction '{entry.name}': '{entry.a}' twice (a pair of two vessels)")
        entry_names = [e.name for e in list(pairs) + list(banks) + list(washes)]
        if len(set(entry_names)) != len(entry_names):
            raise ValueError(f"interactions: names {sorted({n for n in entry_names if entry_names.count(n) > 1})} "
                             "used twice")
        self.vessels: List[str] = names              # every vessel that feels a load, in order of mention
        # and every vessel whose state a load needs (a wash's source may feel nothing)
        self.tracked: List[str] = list(dict.fromkeys(names + [w.source for w in washes]))
        self.index = {n: i for i, n in enumerate(names)}
        self.pairs, self.banks, self.washes = list(pairs), list(banks), list(washes)
        self.propulsors = {w.source: list(propulsors[w.source]) for w in washes}
        self._box = {w.target: (hulls[w.target].length, hulls[w.target].beam, float(drafts[w.target]))
                     for w in washes}
        self.depth = float(depth)
        curves = [hulls[n] for n in names]
        rules = [composite_gauss(c.length, nodes) for c in curves]
        self._x1 = np.array([x for x, _ in rules])
        self._sway_w1 = np.array([w * c.slope(x) for c, (x, w) in zip(curves, rules)])
        self._yaw_w1 = np.array([w * (c.area(x) + x * c.slope(x)) for c, (x, w) in zip(curves, rules)])
        self._half_length = np.array([0.5 * c.length for c in curves])
        self._slope = np.array([8.0 * c.midship_area / c.length ** 2 for c in curves])
        self._length = np.array([c.length for c in curves])
        self._beam = np.array([c.beam for c in curves])
        self._rho = np.array([float(density[n]) for n in names])
        self._hull_of = np.arange(len(names), dtype=np.int64)
        self._pair_a = np.array([self.index[p.a] for p in self.pairs], dtype=np.int64)
        self._pair_b = np.array([self.index[p.b] for p in self.pairs], dtype=np.int64)
        self._images = 0 if math.isinf(self.depth) else IMAGE_COUNT
        for entry in self.banks:
            if entry.bank is None and depth_field is None:
                raise ValueError(f"interaction '{entry.name}': the banks of a depth field, and no depth_field given")
        self.depth_field = depth_field
        self._bank_effects = [BankEffect(hulls[e.vessel], nodes, density[e.vessel]) for e in self.banks]
        self._states = np.zeros((len(names), 5))
        self._loads = np.zeros((len(names), 3))
        self._off = np.zeros(len(self.pairs), dtype=np.int64)

    def loads(self, states: Dict[str, PlanarState], lead: float,
              thrust: Dict[str, Sequence[Tuple[float, float]]] = None) -> Tuple[
            Dict[str, Tuple[float, float, float]], Dict[str, bool]]:
        """({vessel: (X, Y, N) summed over its entries}, {entry name: off}) with every state
        carried on `lead` s; `thrust`: each wash source's (thrust N, azimuth rad) per propulsor,
        held over the lead (absent: no wash)."""
        for i, name in enumerate(self.vessels):
            self._states[i] = states[name]
        _pair_loads(self._states, float(lead), self._pair_a, self._pair_b, self._hull_of, self._x1, self._sway_w1,
                    self._yaw_w1, self._half_length, self._slope, self._length, self._beam,
                    0.0 if math.isinf(self.depth) else self.depth, self._images, self._rho, self._loads, self._off)
        off = {p.name: bool(o) for p, o in zip(self.pairs, self._off)}
        for entry, effect in zip(self.banks, self._bank_effects):
            own = ahead(states[entry.vessel], lead)
            speed = math.cos(own.yaw) * own.vx + math.sin(own.yaw) * own.vy
            try:
                if entry.bank is None:     # the depth field's banks across the ship
                    y, n = effect.loads_in_depth(self.depth_field, own.x, own.y, own.yaw, speed)
                else:
                    y, n = effect.loads_along(entry.bank, own.x, own.y, own.yaw, speed, self.depth, entry.slope)
            except ValueError:        # inside the half beam of the bank or beyond it: the model's limit
                off[entry.name] = True
                continue
            off[entry.name] = False
            row = self._loads[self.index[entry.vessel]]
            row[1] += y
            row[2] += n
        for entry in self.washes:
            units = (thrust or {}).get(entry.source)
            if units is None:
                continue
            y, n = self.wash_load(entry, ahead(states[entry.source], lead), ahead(states[entry.target], lead), units)
            row = self._loads[self.index[entry.target]]
            row[1] += y
            row[2] += n
        return {name: tuple(float(v) for v in self._loads[i]) for i, name in enumerate(self.vessels)}, off

    def wash_load(self, entry: WashEntry, source: PlanarState, target: PlanarState,
                  units: Sequence[Tuple[float, float]]) -> Tuple[float, float]:
        """The sway force and yaw moment (target's body axes, about midship) of `entry`'s jets: each
        propulsor's jet leaves it against its thrust (with the thrust when reversed) and carries the
        thrust's momentum (propeller_wash)."""
        props = self.propulsors[entry.source]
        if len(units) != len(props):
            raise ValueError(f"interaction '{entry.name}': {len(units)} thrusts for {len(props)} propulsors "
                             f"of '{entry.source}'")
        length, beam, draft = self._box[entry.target]
        cs, ss = math.cos(source.yaw), math.sin(source.yaw)
        ct, st = math.cos(target.yaw), math.sin(target.yaw)
        fy = fn = 0.0
        for prop, (t, azimuth) in zip(props, units):
            if t == 0.0:
                continue
            wx = source.x + cs * prop.x - ss * prop.y - target.x      # the propeller, from the target's midship
            wy = source.y + ss * prop.x + cs * prop.y - target.y
            jet = math.pi + source.yaw + azimuth if t > 0.0 else source.yaw + azimuth   # jet heading (world)
            jx, jy = math.cos(jet), math.sin(jet)
            y, n = wash_on_hull(abs(t), prop.d0, prop.depth, entry.impingement, ct * wx + st * wy,
                                -st * wx + ct * wy, ct * jx + st * jy, -st * jx + ct * jy, length, beam, draft,
                                GAUSS_X, GAUSS_W)
            fy += y
            fn += n
        return fy, fn
