"""Schema of the displacement ship file (``model: displacement``): pydantic models, one per
section, unknown keys forbidden, numbers strictly typed (no strings or booleans), finite and
inside physical ranges. ship_file.load_ship validates a file with ``validate_displacement``
and builds the model from the result. (Planing-hull files, ``model: planing_6dof``, are
checked key by key by planing.PlaningHull.from_config against its own table.)

Ranges admit the shipped files (a 5 m tank model of a barge to the 175 m S-175) and the real
span of ships, about 10 m harbour craft to 400+ m carriers, with margin; they refuse values no
ship has, which today make the state non-finite (mass 1e-9 kg, engine lag 1e-9 s) or the run
endless (max_substep 1e-7 s). Checks between sections (mass against the hull's volume, lags
against the integration step, points on the hull) are in ``cross_checks``.
"""
from __future__ import annotations

import math
from typing import Any, Dict, List, Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Field
from typing_extensions import Annotated

from sea_environment.wind_loads import BLENDERMANN_TABLE

G = 9.80665


class _S(BaseModel):
    # strict: 1 is a number, "1" and true are not; no NaN or inf; unknown keys are errors
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)


def _num(lo: Optional[float] = None, hi: Optional[float] = None, *, gt: Optional[float] = None, default: Any = ...):
    return Field(default, ge=lo, le=hi, gt=gt)


Vec3 = Annotated[List[float], Field(min_length=3, max_length=3)]
Vec2 = Annotated[List[float], Field(min_length=2, max_length=2)]
# non-dimensional hydrodynamic derivatives are O(1e-4 .. 1); |value| <= 10 only catches typos
Deriv = Annotated[float, Field(ge=-10.0, le=10.0)]
# added-mass derivatives: minus the added mass, so never positive (the mass matrix must stay
# positive definite)
AddedDeriv = Annotated[float, Field(ge=-10.0, le=0.0)]


class PolyDerivatives(_S):
    """Yun & Kim (barge) Eq 2 (prime system of their Eq 4)."""
    Xudot: AddedDeriv
    Yvdot: AddedDeriv
    Yrdot: Deriv
    Nvdot: Deriv
    Nrdot: AddedDeriv
    Xvv: Deriv
    Xrr: Deriv
    Xvr: Deriv
    Yv: Deriv
    Yvav: Deriv
    Yr: Deriv
    Yrar: Deriv
    Yvrr: Deriv
    Yrvv: Deriv
    Nv: Deriv
    Nvav: Deriv
    Nr: Deriv
    Nrar: Deriv
    Nvrr: Deriv
    Nrvv: Deriv


class LowSpeedDerivatives(_S):
    """S. D. Yoon (anchor dredging) Eq 3 (forces / 0.5 rho L d V^2)."""
    Xuu: Deriv
    Xvr: Deriv
    Yv: Deriv
    Yr: Deriv
    Yvv: Deriv
    Yvr: Deriv
    Yrr: Deriv
    Nv: Deriv
    Nr: Deriv
    Nvvr: Deriv
    Nvrr: Deriv
    Nrr: Deriv


class CrossflowDerivatives(_S):
    """Cross-flow hull (maneuvering._hull_crossflow), forces / 0.5 rho L d V^2 as LowSpeedDerivatives:
    the linear (lift) derivatives and X'uu, X'vr; Y'vv = -C_D, the sectional cross-flow drag
    coefficient of the strip integral (Hooft 1994; for a uniform strip Y'vv = -C_D exactly)."""
    Xuu: Deriv
    Xvr: Deriv
    Yv: Deriv
    Yr: Deriv
    Nv: Deriv
    Nr: Deriv
    Yvv: Annotated[float, Field(ge=-10.0, le=0.0)]    # -C_D: drag opposes the cross-flow


class CrossflowPlane(_S):
    """The lateral plane of the strip integral: x_aft..x_fore (m, body frame, default -L/2..L/2)."""
    x_aft: float
    x_fore: float


class AddedMass(_S):
    # measured / estimated ratios: surge 0.02-0.1, sway 0.2-1.5 (a flat barge to a deep hull),
    # yaw 0.01-0.1; the bounds are several times those
    mx_over_m: float = _num(0.0, 2.0)
    my_over_m: float = _num(0.0, 5.0)
    Jz_over_mL2: float = _num(0.0, 0.5)


class Resistance(_S):
    """Straight-running resistance table: speeds increasing from >= 0, forces >= 0."""
    speed: Annotated[List[Annotated[float, Field(ge=0.0, le=40.0)]], Field(min_length=1, max_length=200)]
    # 1e8 N: ten times the resistance of the largest ships at their top speed
    force: Annotated[List[Annotated[float, Field(ge=0.0, le=1e8)]], Field(min_length=1, max_length=200)]


class _Hull(_S):
    enabled: bool = True                 # false: no hull forces and no added mass (a rigid body)
    length: float = _num(1.0, 500.0)     # m: tank models (5 m barge) .. the largest ships (~460 m)
    beam: float = _num(0.1, 100.0)       # m: widest ships ~70 m
    draft: float = _num(0.05, 40.0)      # m: a 0.3 m model .. ULCC ~30 m
    mass: float = _num(1.0, 1e9)         # kg: a tank model .. 650 000 t; see cross_checks (block coefficient)
    x_g: float = 0.0                     # m, |x_g| <= L/2 (cross_checks)
    yaw_radius_of_gyration: float = _num(gt=0.0)  # m, 0.05 L .. 0.5 L (cross_checks)
    resistance: Optional[Resistance] = None


class PolynomialHull(_Hull):
    form: Literal["polynomial"]
    derivatives: PolyDerivatives         # added mass from Xudot, Yvdot, Yrdot, Nvdot, Nrdot


class LowSpeedHull(_Hull):
    form: Literal["lowspeed"]
    derivatives: LowSpeedDerivatives
    added_mass: AddedMass
    # the hull's cross-flow drag coefficient at 90 deg drift (force / 0.5 rho L d v^2) in deep water;
    # None: -Yvv, what the derivatives imply (README "Beam-on drag"); ships 0.5-1.2, a flat plate 2
    beam_on_drag: Optional[Annotated[float, Field(gt=0.0, le=3.0)]] = None


class CrossflowHull(_Hull):
    """Valid at any drift angle (escort / indirect towing): linear lift terms continued as
    sin(b) cos(b) plus Hooft's cross-flow drag integral (Oltmann & Sharma 1984; Hooft 1994)."""
    form: Literal["crossflow"]
    derivatives: CrossflowDerivatives
    added_mass: AddedMass
    crossflow: Optional[CrossflowPlane] = None


HULL_FORMS = ("polynomial", "lowspeed", "crossflow")
Hull = Annotated[Union[PolynomialHull, LowSpeedHull, CrossflowHull], Field(discriminator="form")]


class Engine(_S):
    rated_rpm: float = _num(1.0, 5000.0)  # propeller rpm: slow-speed diesels 60-100 .. small craft ~3000
    # engine lag (S. D. Yoon Eq 9): diesels take seconds; 0.05 s is faster than any real engine
    # and keeps the explicit RK4 sub-step stable (also checked against max_substep)
    time_constant: float = _num(0.05, 600.0)


class Propeller(_S):
    position: Vec3
    diameter: float = _num(0.01, 15.0)    # m: model propellers .. ~11 m on the largest ships
    pitch_ratio: float = _num(0.3, 2.5)   # P/D of real propellers 0.5-1.6
    kt: Vec3                              # K_T(J) = c1 + c2 J + c3 J^2; |c| <= 5 (cross_checks)
    wake_fraction: float = _num(0.0, 0.9)
    thrust_deduction: float = _num(0.0, 0.9)
    astern_factor: float = _num(0.0, 1.5)
    ducted: bool = False                  # in a nozzle: its jet leaves at D, an open one's at D/sqrt(2) (wash)


class OpenWater(_S):
    """Open-water data of a (ducted) propeller: K_T (total, propeller + nozzle) at advance
    ratios J; ship_file fits K_T = c1 + c2 J + c3 J^2 by least squares."""
    J: Annotated[List[Annotated[float, Field(ge=0.0, le=2.0)]], Field(min_length=3, max_length=40)]
    KT: Annotated[List[Annotated[float, Field(ge=-2.0, le=2.0)]], Field(min_length=3, max_length=40)]


class DeductionTable(_S):
    """Thrust deduction as a function of the azimuth (deg, -180..180, increasing), linear between
    the points and periodic over 360 deg."""
    azimuth_deg: Annotated[List[Annotated[float, Field(ge=-180.0, le=180.0)]], Field(min_length=1, max_length=12)]
    value: Annotated[List[Annotated[float, Field(ge=0.0, le=0.9)]], Field(min_length=1, max_length=12)]


class Thruster(_S):
    """An azimuth thruster (ASD tug, Z-drive, pod): thrust along its azimuth, own engine."""
    name: Optional[str] = None                  # default "thruster<k>"
    position: Vec3                              # m, propeller centre, body frame
    diameter: float = _num(0.1, 10.0)           # m: harbour-tug units 1.6-3.4 m
    kt: Optional[Vec3] = None                   # K_T(J) = c1 + c2 J + c3 J^2 (total thrust), or
    open_water: Optional[OpenWater] = None      # open-water points (exactly one of the two)
    wake_fraction: float = _num(0.0, 0.9, default=0.0)
    thrust_deduction: Union[Annotated[float, Field(ge=0.0, le=0.9)], DeductionTable]
    reversible: bool = False                    # rpm orders -1..1 (a reversing drive) instead of 0..1
    astern_factor: float = _num(0.0, 1.5, default=0.65)   # K_T scale with reversed rotation
    rated_rpm: float = _num(1.0, 5000.0)        # propeller rpm at rpm order 1
    time_constant: float = _num(0.05, 600.0)    # s, rpm lag (S. D. Yoon Eq 9 form)
    slew_rate_deg_s: float = _num(0.5, 360.0)   # deg/s; harbour-tug units 10-30
    azimuth_time_constant: float = _num(0.05, 10.0, default=0.5)  # s, lag of the last few degrees
    full_360: bool = True                       # turns without stops (shortest way round)
    azimuth_range_deg: Optional[Vec2] = None    # [lo, hi] deg within -180..180 when full_360 is false
    ducted: bool = False                        # in a nozzle: its jet leaves at D, an open one's at D/sqrt(2) (wash)


class Steering(_S):
    max_angle_deg: float = _num(1.0, 90.0)    # rudders 35-45 deg; flap / vector rudders up to 70-90
    time_constant: float = _num(0.05, 600.0)  # s, steering-gear lag (S. D. Yoon Eq 10); see Engine
    max_rate_deg_s: float = _num(0.1, 100.0)  # SOLAS minimum 2.3 deg/s; fast tug gear ~10


class Rudder(_S):
    position: Vec3
    area: float = _num(gt=0.0)             # m^2, at most 0.1 L T (cross_checks); ships 0.015-0.05 L T
    aspect_ratio: float = _num(0.2, 6.0)
    height: Optional[float] = _num(gt=0.0, default=None)   # m, default sqrt(aspect_ratio area)
    propeller: Optional[int] = None        # index into propellers, or null
    a_H: float = _num(0.0, 1.0)
    x_H: float                             # m, |x_H| <= L (cross_checks)
    t_R: float = _num(0.0, 1.0)
    wake_fraction: float = _num(0.0, 0.9)
    l_R: float = _num(-2.0, 2.0)           # non-dimensional (x L); MMG values -0.7 .. -1.0
    kappa_factor: float = _num(gt=0.0, default=0.6)


class Roll(_S):
    gm: float = _num(0.01, 20.0)                 # m; ships 0.15-5 m, small craft up to ~10 m
    bm: float = _num(0.01, 200.0)                # m; wide shallow barges have large BM
    radius_of_gyration: float = _num(gt=0.0)     # m, at most the beam (cross_checks); ships 0.35-0.45 B
    added_inertia_ratio: float = _num(0.0, 2.0)
    z_g: float                                   # m, |z_g| <= L (cross_checks)
    damping_ratio: float = _num(0.0, 2.0)
    z_lateral_resistance: float = _num(hi=0.0)   # m, within the draft: -T .. 0 (cross_checks)
    freeboard: float = _num(0.01, 50.0)          # m
    girting_threshold: float = _num(0.01, 1.0)   # warning at this fraction of the deck-edge moment


class Anchor(_S):
    holding_coefficient: float = _num(0.0, 20.0)         # lambda_a; dredging anchors 1-10
    weight_in_water: float = _num(1.0, 1e7)              # N; the largest anchors and chain < 1e6 N
    moment_lever: float = _num(0.0)                      # m, at most 2 L (cross_checks)
    let_go_time: float = _num(0.0, 3600.0)               # s
    heave_up_time: float = _num(0.1, 7200.0)             # s
    side: Literal["auto", "port", "starboard"] = "auto"
    speed_regularisation: float = _num(1e-3, 5.0, default=0.05)   # m/s
    turning_threshold: float = _num(1e-3, 1.0, default=0.05)      # r'
    max_drift_ratio: float = _num(1e-3, 10.0, default=1.0)
    turning_fade_speed: float = _num(1e-3, 10.0, default=0.5)     # m/s
    # The chain (optional; both or neither): with them and a scenario depth the anchor holds at most
    # what the chain's catenary can take with its lowest point still at the anchor (maneuvering.py,
    # anchor_holding_factor); without them, or without a depth, it holds as the paper's model.
    chain_out: Optional[float] = Field(None, gt=0.0, le=2000.0)     # m of chain out when let go
    chain_weight: Optional[float] = Field(None, gt=0.0, le=1e5)     # N/m, submerged weight per metre
    hawse_height: float = _num(0.0, 50.0, default=0.0)              # m, hawse pipe above the waterline


class TowlineSimple(_S):
    """Yun & Kim (barge) Eq 3: a towline force of fixed size at an angle that swings to gamma_max."""
    enabled: bool = False
    force: Union[Literal["resistance"], Annotated[float, Field(gt=0.0, le=1e8)]] = "resistance"
    reference_speed: Optional[float] = _num(gt=0.0, hi=40.0, default=None)   # m/s, for force: resistance
    lever: Optional[float] = None            # m, default L/2; |lever| <= L (cross_checks)
    drift_sign: float = _num(-1.0, 1.0, default=1.0)
    gamma_rate_deg_s: float = _num(gt=0.0, hi=90.0)
    gamma_max_deg: float = _num(-90.0, 90.0)


class Windage(_S):
    """Above-water particulars for the wind loads (Blendermann 1994, sea_environment.wind_loads)."""
    type: Literal[tuple(BLENDERMANN_TABLE)]          # Blendermann's ship type
    frontal_area: float = _num(gt=0.0)               # m^2, A_F, projected on the midship section
    lateral_area: float = _num(gt=0.0)               # m^2, A_L, projected on the centreplane
    centroid_x: float                                # m, A_L's centroid forward of the reference point
    centroid_height: float = _num(gt=0.0)            # m, A_L's centroid above the waterline
    length_overall: float = _num(gt=0.0)             # m


class Integration(_S):
    # RK4 sub-step: 1 ms (20 sub-steps per 50 Hz exchange) .. 2 s; smaller only burns CPU
    # (1e-7 s would take days per simulated minute), larger misses the time constants
    max_substep: float = _num(1e-3, 2.0)


class DisplacementShip(_S):
    model: Literal["displacement"]
    name: Optional[str] = None
    description: Optional[str] = None
    sources: Optional[Union[List[str], Dict[str, str]]] = None
    notes: Optional[Union[str, List[str]]] = None
    estimated: Optional[Dict[str, str]] = None
    # fresh water (1000) .. brine (~1240) would be physical; 900-1100 as the scenario's environment
    water_density: float = _num(900.0, 1100.0)
    hull: Hull
    engine: Optional[Engine] = None
    propellers: Optional[Annotated[List[Propeller], Field(max_length=4)]] = None
    steering: Optional[Steering] = None
    rudders: Optional[Annotated[List[Rudder], Field(max_length=4)]] = None
    thrusters: Optional[Annotated[List[Thruster], Field(min_length=1, max_length=4)]] = None
    # thruster-thruster interaction: "abs" = ABS DP guide (2013) Appendix 1 jet reduction; "none"
    thruster_interaction: Literal["abs", "none"] = "abs"
    roll: Optional[Roll] = None
    anchor: Optional[Anchor] = None
    towline_simple: Optional[TowlineSimple] = None
    attachments: Optional[Dict[str, Vec3]] = None
    integration: Optional[Integration] = None
    windage: Optional[Windage] = None
    current: Vec2 = Field(default_factory=lambda: [0.0, 0.0])   # m/s east, north; |c| <= 10 (cross_checks)


def _default_hmax(length: float) -> float:
    return 0.1 * math.sqrt(length / G)


def cross_checks(s: DisplacementShip) -> List[tuple]:
    """Checks between keys: [(dotted key, message)], empty when the file is consistent."""
    L = s.hull.length
    out = _check_hull(s.hull, s.water_density)
    hmax = s.integration.max_substep if s.integration else _default_hmax(L)
    out += _check_engine_and_steering_lags(s, hmax)
    out += _check_thrusters(s.thrusters or [], L, hmax)
    out += _check_anchor_chain(s.anchor)
    props = s.propellers or []
    out += _check_drive_sections(s, props)
    out += _check_propellers(props, L)
    out += _check_rudders(s.rudders or [], len(props), s.hull)
    out += _check_roll(s.roll, s.hull, hmax)
    out += _check_anchor_lever(s.anchor, L)
    out += _check_towline(s.towline_simple, s.hull)
    out += _check_attachments(s.attachments or {}, L)
    out += _check_current(s.current)
    return out


def _check_hull(h: Hull, water_density: float) -> List[tuple]:
    """The hull's particulars must describe a real hull: a plausible fullness, the centre of
    gravity and the lateral plane on it, a gyration radius ships have."""
    out = []
    L, B, T = h.length, h.beam, h.draft
    cb = h.mass / (water_density * L * B * T)
    # the block coefficient of real hulls is 0.35 (fast craft) .. 0.9 (barges); 0.1-1.1 allows
    # for overhangs and for L, B, T not quite the displacement's
    if not 0.1 <= cb <= 1.1:
        out.append(("hull.mass", f"{h.mass:g} kg gives a block coefficient m / (rho L B T) = {cb:.3g}; "
                                 "expected 0.1 .. 1.1 (check mass, length, beam, draft)"))
    if abs(h.x_g) > 0.5 * L:
        out.append(("hull.x_g", f"{h.x_g:g} m is off the hull (|x_g| <= L/2 = {0.5 * L:g} m)"))
    if not 0.05 * L <= h.yaw_radius_of_gyration <= 0.5 * L:
        # 0.5 L: all the mass at the ends; real ships 0.22-0.3 L
        out.append(("hull.yaw_radius_of_gyration",
                    f"{h.yaw_radius_of_gyration:g} m; expected 0.05 L .. 0.5 L ({0.05 * L:g} .. {0.5 * L:g} m)"))
    cf = getattr(h, "crossflow", None)
    if cf is not None:
        # the lateral plane lies on the hull (its ends at most L from the reference point)
        if not -L <= cf.x_aft < cf.x_fore <= L:
            out.append(("hull.crossflow", f"x_aft {cf.x_aft:g} .. x_fore {cf.x_fore:g} m: expected "
                                          f"-L <= x_aft < x_fore <= L ({L:g} m)"))
    if h.resistance is not None:
        out += _check_resistance_table(h.resistance)
    return out


def _check_resistance_table(res: Resistance) -> List[tuple]:
    """The resistance curve is interpolated in speed: one force per speed, speeds increasing."""
    v, f = res.speed, res.force
    if len(v) != len(f):
        return [("hull.resistance.force", f"{len(f)} values for {len(v)} speeds")]
    if any(b <= a for a, b in zip(v, v[1:])):
        return [("hull.resistance.speed", "speeds must increase")]
    return []


def _check_lag(key: str, time_constant: float, hmax: float) -> List[tuple]:
    """A first-order lag faster than the RK4 sub-step can follow would blow the state up."""
    # RK4 is stable for a first-order lag while h / T < 2.78: keep a margin of 1.4
    if time_constant < 0.5 * hmax:
        return [(key, f"{time_constant:g} s is shorter than half the integration sub-step "
                      f"({hmax:g} s, integration.max_substep): the lag would be unstable")]
    return []


def _check_engine_and_steering_lags(s: DisplacementShip, hmax: float) -> List[tuple]:
    """The engine's and the steering gear's lags are integrated with the ship's sub-step."""
    out = []
    for key, sec in (("engine.time_constant", s.engine), ("steering.time_constant", s.steering)):
        if sec is not None:
            out += _check_lag(key, sec.time_constant, hmax)
    return out


def _check_kt(key: str, kt: List[float]) -> List[tuple]:
    """A K_T(J) polynomial must give thrust at the bollard (J = 0) and have sane coefficients."""
    out = []
    if kt[0] <= 0.0:
        out.append((key, f"K_T at J = 0 must be positive, got {kt[0]:g}"))
    if any(abs(c) > 5.0 for c in kt):
        out.append((key, f"coefficients beyond +-5: {kt}"))
    return out


def _check_thrusters(thrusters: List[Thruster], L: float, hmax: float) -> List[tuple]:
    """Each azimuth thruster: on the ship, a name of its own (orders and telemetry address it),
    one source of K_T, usable tables, lags the sub-step resolves, a valid azimuth range."""
    out = []
    names = set()
    for i, th in enumerate(thrusters):
        key = f"thrusters.{i}"
        out += _point(f"{key}.position", th.position, L)
        name = th.name if th.name is not None else f"thruster{i}"
        if name in names:
            out.append((f"{key}.name", f"{name!r} is used by another thruster"))
        names.add(name)
        out += _check_thruster_thrust_curve(key, th)
        out += _check_deduction_table(key, th.thrust_deduction)
        for sub, tc in (("time_constant", th.time_constant), ("azimuth_time_constant", th.azimuth_time_constant)):
            out += _check_lag(f"{key}.{sub}", tc, hmax)
        out += _check_azimuth_range(key, th)
    return out


def _check_thruster_thrust_curve(key: str, th: Thruster) -> List[tuple]:
    """K_T comes from exactly one of the polynomial and the open-water points (fitted by
    ship_file), each of which must be usable."""
    out = []
    if (th.kt is None) == (th.open_water is None):
        out.append((f"{key}.kt", "give exactly one of kt and open_water"))
    if th.kt is not None:
        out += _check_kt(f"{key}.kt", th.kt)
    if th.open_water is not None and len(th.open_water.J) != len(th.open_water.KT):
        out.append((f"{key}.open_water.KT", f"{len(th.open_water.KT)} values for {len(th.open_water.J)} J"))
    return out


def _check_deduction_table(key: str, td: Union[float, DeductionTable]) -> List[tuple]:
    """A thrust-deduction table is interpolated periodically in azimuth: one value per azimuth,
    azimuths increasing and spanning less than a full turn."""
    if not isinstance(td, DeductionTable):
        return []
    if len(td.azimuth_deg) != len(td.value):
        return [(f"{key}.thrust_deduction.value", f"{len(td.value)} values for {len(td.azimuth_deg)} azimuths")]
    if any(b <= a for a, b in zip(td.azimuth_deg, td.azimuth_deg[1:])):
        return [(f"{key}.thrust_deduction.azimuth_deg", "azimuths must increase")]
    if td.azimuth_deg[-1] - td.azimuth_deg[0] >= 360.0:
        return [(f"{key}.thrust_deduction.azimuth_deg", "-180 and 180 are the same azimuth: give one")]
    return []


def _check_azimuth_range(key: str, th: Thruster) -> List[tuple]:
    """A unit with stops needs its range (lo < hi within -180..180); a full_360 unit has none."""
    if th.full_360:
        if th.azimuth_range_deg is not None:
            return [(f"{key}.azimuth_range_deg", "a full_360 unit has no range (set full_360: false)")]
        return []
    r = th.azimuth_range_deg
    if r is None:
        return [(f"{key}.azimuth_range_deg", "required key is missing (full_360: false)")]
    if not -180.0 <= r[0] < r[1] <= 180.0:
        return [(f"{key}.azimuth_range_deg", f"{r}: need -180 <= lo < hi <= 180 deg")]
    return []


def _check_anchor_chain(a: Optional[Anchor]) -> List[tuple]:
    """The chain's catenary limit needs both its length and its weight (or neither)."""
    if a is not None and (a.chain_out is None) != (a.chain_weight is None):
        return [(f"anchor.{'chain_weight' if a.chain_weight is None else 'chain_out'}",
                 "chain_out and chain_weight go together (or neither)")]
    return []


def _check_drive_sections(s: DisplacementShip, props: List[Propeller]) -> List[tuple]:
    """Propellers turn at the engine's rpm and rudders at the steering gear's rate: the
    sections they depend on must be there."""
    out = []
    if props and s.engine is None:
        out.append(("engine", "propellers need an 'engine' section (rated_rpm, time_constant)"))
    if s.rudders and s.steering is None:
        out.append(("steering", "rudders need a 'steering' section"))
    return out


def _check_propellers(props: List[Propeller], L: float) -> List[tuple]:
    """Each propeller on the ship with a usable K_T polynomial."""
    out = []
    for i, p in enumerate(props):
        out += _point(f"propellers.{i}.position", p.position, L)
        out += _check_kt(f"propellers.{i}.kt", p.kt)
    return out


def _check_rudders(rudders: List[Rudder], n_propellers: int, h: Hull) -> List[tuple]:
    """Each rudder on the ship, of a size ships have, behind an existing propeller (or none)."""
    out = []
    L, T = h.length, h.draft
    for i, r in enumerate(rudders):
        out += _point(f"rudders.{i}.position", r.position, L)
        if r.area > 0.1 * L * T:
            out.append((f"rudders.{i}.area", f"{r.area:g} m^2 is more than 0.1 L T = {0.1 * L * T:g} m^2"))
        if abs(r.x_H) > L:
            out.append((f"rudders.{i}.x_H", f"{r.x_H:g} m is off the hull (|x_H| <= L)"))
        if r.propeller is not None and not 0 <= r.propeller < n_propellers:
            out.append((f"rudders.{i}.propeller",
                        f"must be an index into propellers (0..{n_propellers - 1}) or null, got {r.propeller}"))
    return out


def _check_roll(ro: Optional[Roll], h: Hull, hmax: float) -> List[tuple]:
    """Roll particulars within the hull, and a roll period the RK4 sub-step can resolve."""
    if ro is None:
        return []
    out = []
    L, B, T = h.length, h.beam, h.draft
    if ro.radius_of_gyration > B:
        out.append(("roll.radius_of_gyration", f"{ro.radius_of_gyration:g} m is more than the beam ({B:g} m)"))
    if abs(ro.z_g) > L:
        out.append(("roll.z_g", f"{ro.z_g:g} m is off the hull"))
    if ro.z_lateral_resistance < -T:
        out.append(("roll.z_lateral_resistance", f"{ro.z_lateral_resistance:g} m is below the keel (-{T:g} m)"))
    # the roll oscillation must be resolved by the RK4 sub-step (omega h < 1.6)
    kxx2 = ro.radius_of_gyration ** 2 * (1.0 + ro.added_inertia_ratio) + ro.z_g ** 2
    period = 2.0 * math.pi * math.sqrt(kxx2 / (G * ro.gm))
    if period < 4.0 * hmax:
        out.append(("roll.gm", f"roll period {period:.3g} s is shorter than 4 integration sub-steps "
                               f"({hmax:g} s): lower gm or integration.max_substep"))
    return out


def _check_anchor_lever(a: Optional[Anchor], L: float) -> List[tuple]:
    """The anchor's yaw-moment lever is a point on or near the ship."""
    if a is not None and a.moment_lever > 2.0 * L:
        return [("anchor.moment_lever", f"{a.moment_lever:g} m is more than 2 L")]
    return []


def _check_towline(t: Optional[TowlineSimple], h: Hull) -> List[tuple]:
    """A towline sized from the resistance needs the resistance curve and a speed to read it
    at; its lever is on the hull."""
    if t is None:
        return []
    out = []
    if t.force == "resistance":
        if t.reference_speed is None:
            out.append(("towline_simple.reference_speed", "required key is missing (force: resistance)"))
        if h.resistance is None:
            out.append(("towline_simple.force", "'resistance' needs hull.resistance"))
    if t.lever is not None and abs(t.lever) > h.length:
        out.append(("towline_simple.lever", f"{t.lever:g} m is off the hull (|lever| <= L)"))
    return out


def _check_attachments(attachments: Dict[str, List[float]], L: float) -> List[tuple]:
    """Rope and fender attachment points are on the ship."""
    out = []
    for k, p in attachments.items():
        out += _point(f"attachments.{k}", p, L)
    return out


def _check_current(current: List[float]) -> List[tuple]:
    """The ship's own current (m/s east, north) stays within what seas have."""
    if any(abs(c) > 10.0 for c in current):
        return [("current", f"{current} m/s: components must be within +-10 m/s")]
    return []


def _point(key: str, p: List[float], L: float) -> List[tuple]:
    # a body point further than one ship length from the origin is not on the ship
    if any(abs(c) > L for c in p):
        return [(key, f"{p} m is not on the ship (each coordinate within +-L = {L:g} m)")]
    return []
