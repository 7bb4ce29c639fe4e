"""Ship files: YAML descriptions of vessels; ``load_ship`` builds the model a file names.

The key ``model:`` selects the class:
  displacement   tug_dynamics.maneuvering.ManeuveringVessel (this module builds it)
  planing_6dof   tug_dynamics.planing.PlaningHull.from_config(cfg, source, name, initial_state)

Every error names the file and the dotted key. Unknown keys are errors (typos would
otherwise silently fall back to defaults), so are duplicate keys, strings or booleans for
numbers, NaN / inf and values outside physical ranges (schema: ship_schema.py for the
displacement format; planing.py checks its own). ``estimated:`` maps dotted keys to the method
used to estimate them; each listed key must exist in the file.
"""
from __future__ import annotations

import copy
import dataclasses
import glob
import math
import os
import re
from typing import Any, List, Optional, Tuple

import numpy as np
from pydantic import ValidationError

from . import maneuvering as mv
from . import ship_schema as schema
from .vessel import Vessel, VesselState
from sim_math.data_files import package_data_dir
from sim_math.input_files import YamlInputError, load_yaml

G = 9.80665


class ShipFileError(ValueError):
    """A ship file that cannot be used; the message names the file and the key."""


def ships_dir() -> str:
    """The ships directory (sim_math.data_files: the source tree's ships/, else the share's)."""
    return package_data_dir("tug_dynamics", "ships")


def list_ship_files() -> List[str]:
    """Absolute paths of every ships/*.yaml, sorted."""
    return sorted(glob.glob(os.path.join(ships_dir(), "*.yaml")))


def _deep_merge(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = _deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def _read_yaml(path: str) -> dict:
    try:
        cfg = load_yaml(path)
    except YamlInputError as exc:
        raise ShipFileError(f"{path}: {exc}") from None
    if not isinstance(cfg, dict):
        raise ShipFileError(f"{path}: top level must be a mapping of ship keys, got {type(cfg).__name__}")
    return cfg


# the parts of a pydantic error location that name a union's branch, not a key of the file
_BRANCH = re.compile(r"^(literal\[.*\]|constrained-\w+|function-\w+.*|float|int|str|bool|none|list\[.*\]|dict\[.*\])$")


def _dotted(loc) -> str:
    parts = [str(p) for p in loc if not (isinstance(p, str) and _BRANCH.match(p))]
    if len(parts) > 1 and parts[0] == "hull" and parts[1] in schema.HULL_FORMS:
        del parts[1]  # the discriminated union's tag is not a key of the file
    return ".".join(parts)


def _explain(err: dict) -> str:
    kind = err["type"]
    if kind == "extra_forbidden":
        return f"unknown key (misspelt?), value {err['input']!r}"
    if kind == "missing":
        return "required key is missing"
    if kind == "union_tag_invalid":
        return f"unknown hull form {err['input'].get('form')!r} (polynomial | lowspeed | crossflow)"
    if kind == "union_tag_not_found":
        return "required key 'form' is missing (polynomial | lowspeed | crossflow)"
    return f"{err['msg']}, got {err['input']!r}"


def validate_displacement(src: str, cfg: dict, overrides: bool = False) -> schema.DisplacementShip:
    """The file checked against ship_schema; ShipFileError naming the file and every bad key."""
    note = " (after the scenario's ship_overrides)" if overrides else ""
    try:
        ship = schema.DisplacementShip.model_validate(cfg)
    except ValidationError as exc:
        lines = []  # a value failing every branch of a union gives one line per branch: keep the first
        for e in exc.errors():
            key = _dotted(e["loc"]) or "(top)"
            if not any(line.startswith(f"{src}: key '{key}':") for line in lines):
                lines.append(f"{src}: key '{key}': {_explain(e)}{note}")
        if len(lines) > 10:
            lines[10:] = [f"... and {len(lines) - 10} more"]
        raise ShipFileError("\n".join(lines)) from None
    problems = schema.cross_checks(ship)
    if problems:
        raise ShipFileError("\n".join(f"{src}: key '{k}': {msg}{note}" for k, msg in problems))
    return ship


def _check_estimated(src: str, cfg: dict) -> None:
    est = cfg.get("estimated", {}) or {}
    if not isinstance(est, dict):
        raise ShipFileError(f"{src}: key 'estimated': expected a mapping of dotted key -> method")
    for dotted in est:
        node: Any = cfg
        for part in str(dotted).split("."):
            if isinstance(node, dict) and part in node:
                node = node[part]
            elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
                node = node[int(part)]
            else:
                raise ShipFileError(f"{src}: key 'estimated.{dotted}': names a key the file does not have")


def ship_config(path: str, overrides: Optional[dict] = None) -> Tuple[str, dict]:
    """(absolute path, the file's mapping with `overrides` merged in) of a ship file: a path, or
    a bare file name looked up in ships_dir(). ShipFileError naming the file otherwise."""
    if not os.path.exists(path) and not os.path.isabs(path):
        cand = os.path.join(ships_dir(), path)
        if os.path.exists(cand):
            path = cand
    src = os.path.abspath(path)
    if not os.path.isfile(src):
        raise ShipFileError(f"{src}: ship file not found")
    cfg = _read_yaml(src)
    if overrides:
        if not isinstance(overrides, dict):
            raise ShipFileError(f"{src}: overrides must be a mapping, got {type(overrides).__name__}")
        cfg = _deep_merge(cfg, overrides)
    return src, cfg


def load_ship(path: str, name: Optional[str] = None, initial_state: Optional[VesselState] = None,
              *, overrides: Optional[dict] = None) -> Vessel:
    """Build the vessel a ship file describes.

    path: a file path, or a bare file name looked up in ships_dir().
    name: vessel name (default: the file's ``name``). initial_state: default at rest at the origin.
    overrides: nested dict merged over the file before parsing (tests, scenario variants).
    Raises ShipFileError naming the file and the key (also for planing-hull files).
    """
    src, cfg = ship_config(path, overrides)
    model = cfg.get("model")
    if model is None:
        raise ShipFileError(f"{src}: key 'model': required key is missing (displacement | planing_6dof)")
    if model == "planing_6dof":
        from .planing import PlaningHull  # lazy: written separately, checks its keys against its own table
        try:
            return PlaningHull.from_config(cfg, src, name, initial_state)
        except ValueError as exc:  # planing.ShipFileError and the like: one error class for every ship file
            msg = str(exc)
            raise ShipFileError(msg if src in msg else f"{src}: {msg}") from None
    if model != "displacement":
        raise ShipFileError(f"{src}: key 'model': unknown model {model!r} (displacement | planing_6dof)")
    ship = validate_displacement(src, cfg, overrides=bool(overrides))
    vessel = _build_displacement(src, ship, name, initial_state)
    vessel.length = float(ship.hull.length)
    vessel.beam, vessel.draft = float(ship.hull.beam), float(ship.hull.draft)
    vessel.volume = float(ship.hull.mass) / float(ship.water_density)
    if ship.windage is not None:
        from sea_environment.wind_loads import Windage
        w = ship.windage
        try:
            vessel.windage = Windage(w.type, w.frontal_area, w.lateral_area, w.centroid_x, w.centroid_height,
                                     w.length_overall)
        except ValueError as exc:   # names the key: windage.<key>: ...
            raise ShipFileError(f"{src}: key {exc}") from None
    if not overrides:      # an override may remove sections the estimates refer to
        _check_estimated(src, cfg)
    return vessel


_POLY_KEYS = ["Xvv", "Xrr", "Xvr", "Yv", "Yvav", "Yr", "Yrar", "Yvrr", "Yrvv",
              "Nv", "Nvav", "Nr", "Nrar", "Nvrr", "Nrvv"]
_LOW_KEYS = ["Xuu", "Xvr", "Yv", "Yr", "Yvv", "Yvr", "Yrr", "Nv", "Nr", "Nvvr", "Nvrr", "Nrr"]
# cross-flow hull (maneuvering._hull_crossflow): c[0:7]; the lateral plane x_aft, x_fore in c[7:9]
_CROSS_KEYS = ["Xuu", "Xvr", "Yv", "Yr", "Nv", "Nr", "Yvv"]


@dataclasses.dataclass(frozen=True)
class _AddedMass:
    """Added masses (kg, kg m, kg m^2) of the mass matrix: surge, sway, sway-yaw, yaw-sway, yaw."""
    mx: float
    my: float
    m_yr: float
    m_nv: float
    jz: float


_NO_ADDED_MASS = _AddedMass(0.0, 0.0, 0.0, 0.0, 0.0)


def _build_displacement(src: str, ship: schema.DisplacementShip, name: Optional[str],
                        initial_state) -> mv.ManeuveringVessel:
    """The model's arrays from a validated file (ship_schema: every value typed and in range)."""
    hp = np.zeros(mv.NHULL)
    hp[mv.H_RHO] = ship.water_density
    added, rv, rf, table_v, table_f = _hull_section(hp, ship)
    M, roll_cfg = _mass_matrix_and_roll(hp, ship, added)
    props, rated_rps = _engine_and_propellers(hp, ship)
    ruds, max_steer = _steering_and_rudders(hp, ship, props)
    thrs, thr_cfg = _thrusters_section(src, ship)
    anchor_cfg = _anchor_section(hp, ship)
    _towline_section(hp, ship, table_v, table_f)
    att = {str(k): np.asarray(v, float) for k, v in (ship.attachments or {}).items()}
    hmax = ship.integration.max_substep if ship.integration is not None else schema._default_hmax(ship.hull.length)
    cur = ship.current
    if thr_cfg and not props and ship.steering is None:
        max_steer = math.pi      # an ASD tug: steering is the thrusters' azimuth (set_command)
    return mv.ManeuveringVessel(
        name or str(ship.name), hp, np.array(props) if props else np.zeros((0, mv.NPROP)),
        np.array(ruds) if ruds else np.zeros((0, mv.NRUD)), rv, rf, M,
        {"max_steering": max_steer, "rated_rps": rated_rps}, att, anchor=anchor_cfg, roll=roll_cfg,
        hmax=hmax, initial_state=initial_state, current=(cur[0], cur[1]), source=src,
        thrusters=np.array(thrs) if thrs else None, thruster_cfg=thr_cfg)


def _hull_section(hp: np.ndarray, ship: schema.DisplacementShip):
    """hull: form and derivatives (Yun & Kim Eq 2, S. D. Yoon Eq 3 or the cross-flow hull), added
    mass, X(u) table.

    Returns the added masses, the resistance table the hull uses (empty with the hull off) and
    the file's table, which the towline's X(u_c) needs even with the hull off."""
    h = ship.hull
    rho = ship.water_density
    L, T, m = h.length, h.draft, h.mass
    hp[mv.H_L], hp[mv.H_T], hp[mv.H_M], hp[mv.H_XG] = L, T, m, h.x_g
    d = h.derivatives
    if h.form == "polynomial":
        keys = _POLY_KEYS
        hp[mv.H_FORM] = mv.FORM_POLY
        q3 = 0.5 * rho * L ** 3       # added-mass derivatives / 0.5 rho L^3 (L^4, L^5), Eq 4
        added = _AddedMass(mx=-d.Xudot * q3, my=-d.Yvdot * q3, m_yr=-d.Yrdot * q3 * L,
                           m_nv=-d.Nvdot * q3 * L, jz=-d.Nrdot * q3 * L * L)
        hp[mv.H_MMG_CORIOLIS] = 0.0
    else:
        keys = _LOW_KEYS if h.form == "lowspeed" else _CROSS_KEYS
        hp[mv.H_FORM] = mv.FORM_LOWSPEED if h.form == "lowspeed" else mv.FORM_CROSSFLOW
        am = h.added_mass
        added = _AddedMass(mx=am.mx_over_m * m, my=am.my_over_m * m, m_yr=0.0, m_nv=0.0,
                           jz=am.Jz_over_mL2 * m * L * L)
        hp[mv.H_MMG_CORIOLIS] = 1.0
    for i, k in enumerate(keys):
        hp[mv.H_C0 + i] = getattr(d, k)
    hp[mv.H_SW_CD0] = _deep_crossflow_drag(h, d)
    if h.form == "lowspeed":
        hp[mv.H_C0 + 12] = -hp[mv.H_SW_CD0] - d.Yvv     # dC_D (maneuvering._hull_lowspeed)
    if h.form == "crossflow":
        cf = h.crossflow
        hp[mv.H_C0 + 7] = cf.x_aft if cf is not None else -0.5 * L
        hp[mv.H_C0 + 8] = cf.x_fore if cf is not None else 0.5 * L
    if h.resistance is not None:
        rv = np.asarray(h.resistance.speed, float)
        rf = np.asarray(h.resistance.force, float)
    else:
        rv = rf = np.zeros(0)
    table_v, table_f = rv, rf
    if not h.enabled:
        # hull forces off: no damping, no added mass (a pure rigid body)
        hp[mv.H_FORM] = mv.FORM_NONE
        added = _NO_ADDED_MASS
        rv = rf = np.zeros(0)
    hp[mv.H_MX], hp[mv.H_MY] = added.mx, added.my
    hp[mv.H_ADD0:mv.H_ADD0 + 3] = added.mx, added.my, added.jz     # deep water: the shallow factors' base
    return added, rv, rf, table_v, table_f


def _deep_crossflow_drag(h, d) -> float:
    """The hull's deep-water beam-on cross-flow C_D (force / 0.5 rho L T v^2): the base of the
    shallow-water cross-flow factor (README "Shallow water" (S9)) and, on a lowspeed hull with
    beam_on_drag, the drag at 90 deg drift."""
    if h.form == "polynomial":
        return -d.Yvav * h.length / h.draft      # Y'v|v| is on 0.5 rho L^2 v^2
    if h.form == "lowspeed" and h.beam_on_drag is not None:
        return h.beam_on_drag
    return -d.Yvv


def _mass_matrix_and_roll(hp: np.ndarray, ship: schema.DisplacementShip, added: _AddedMass):
    """The (u, v, r, p) mass matrix about the reference point and, with a roll: section, the
    roll restoring, damping and girting limits (wall-sided GZ at the deck edge)."""
    h = ship.hull
    m, xg = h.mass, h.x_g
    M = np.zeros((4, 4))
    M[0, 0] = m + added.mx
    M[1, 1] = m + added.my
    M[1, 2] = m * xg + added.m_yr
    M[2, 1] = m * xg + added.m_nv
    M[2, 2] = m * h.yaw_radius_of_gyration ** 2 + m * xg ** 2 + added.jz
    hp[mv.H_ZH] = -0.5 * h.draft
    ro = ship.roll
    if ro is None:
        M[3, 3] = 1.0
        return M, None
    gm, kxx, zg = ro.gm, ro.radius_of_gyration, ro.z_g
    jx = ro.added_inertia_ratio * m * kxx ** 2
    hp[mv.H_ZH] = ro.z_lateral_resistance
    ix = m * kxx ** 2 + m * zg ** 2 + jx
    M[1, 3] = M[3, 1] = -m * zg
    M[3, 3] = ix
    hp[mv.H_ROLL], hp[mv.H_ZG] = 1.0, zg
    hp[mv.H_GMW] = m * G * gm
    hp[mv.H_KP] = 2.0 * ro.damping_ratio * math.sqrt(ix * m * G * gm)
    phi_de = math.atan2(ro.freeboard, 0.5 * h.beam)
    gz = math.sin(phi_de) * (gm + 0.5 * ro.bm * math.tan(phi_de) ** 2)   # wall-sided, deck edge
    roll_cfg = {"gm": gm, "deck_edge_angle": phi_de, "max_righting_moment": m * G * gz,
                "girting_threshold": ro.girting_threshold, "z_lateral_resistance": hp[mv.H_ZH]}
    return M, roll_cfg


def _engine_and_propellers(hp: np.ndarray, ship: schema.DisplacementShip):
    """engine: (S. D. Yoon Eq 9 lag) and propellers: (Eq 4 rows). Returns the rows, rated rps."""
    rated_rps = 0.0
    hp[mv.H_TN] = 1.0
    if ship.engine is not None:
        rated_rps = ship.engine.rated_rpm / 60.0
        hp[mv.H_TN] = ship.engine.time_constant
    props: List[np.ndarray] = []
    for p in ship.propellers or []:
        row = np.zeros(mv.NPROP)
        row[mv.P_X], row[mv.P_Y], row[mv.P_Z] = p.position
        row[mv.P_D] = p.diameter
        row[mv.P_PITCH] = p.pitch_ratio * p.diameter
        row[mv.P_C1], row[mv.P_C2], row[mv.P_C3] = p.kt
        row[mv.P_WP0] = p.wake_fraction
        row[mv.P_T] = p.thrust_deduction
        row[mv.P_AST] = p.astern_factor
        props.append(row)
    hp[mv.H_NPROP] = len(props)
    return props, rated_rps


def fit_open_water(J, KT):
    """Least-squares K_T = c1 + c2 J + c3 J^2 through open-water points; (coefficients, largest
    residual)."""
    J = np.asarray(J, float)
    KT = np.asarray(KT, float)
    A = np.vstack([np.ones_like(J), J, J * J]).T
    c, *_ = np.linalg.lstsq(A, KT, rcond=None)
    return c, float(np.max(np.abs(A @ c - KT)))


def _thrusters_section(src: str, ship: schema.DisplacementShip):
    """thrusters: azimuth thruster rows (maneuvering T_*) and their configurations (name, rated
    rps, 360 deg or range, reversible). Open-water points are fitted by a quadratic K_T(J); a fit
    off by more than 0.02 in K_T is refused (the model's thrust is that quadratic)."""
    rows: List[np.ndarray] = []
    cfgs: List[dict] = []
    interaction = ship.thruster_interaction == "abs"
    for i, th in enumerate(ship.thrusters or []):
        row = np.zeros(mv.NTHR)
        row[mv.T_X], row[mv.T_Y], row[mv.T_Z] = th.position
        row[mv.T_D] = th.diameter
        if th.kt is not None:
            c = th.kt
        else:
            c, resid = fit_open_water(th.open_water.J, th.open_water.KT)
            if resid > 0.02:
                raise ShipFileError(f"{src}: key 'thrusters.{i}.open_water': a quadratic K_T(J) misses a point by "
                                    f"{resid:.3g} (> 0.02); give points of a smooth curve or kt")
            if c[0] <= 0.0:
                raise ShipFileError(f"{src}: key 'thrusters.{i}.open_water': fitted K_T(0) = {c[0]:.3g} <= 0")
        row[mv.T_C1], row[mv.T_C2], row[mv.T_C3] = c
        row[mv.T_AST] = th.astern_factor
        row[mv.T_W] = th.wake_fraction
        row[mv.T_TN] = th.time_constant
        row[mv.T_RATE] = math.radians(th.slew_rate_deg_s)
        row[mv.T_TAZ] = th.azimuth_time_constant
        row[mv.T_FULL] = 1.0 if th.full_360 else 0.0
        rng = (-math.pi, math.pi) if th.full_360 else tuple(math.radians(a) for a in th.azimuth_range_deg)
        row[mv.T_AMIN], row[mv.T_AMAX] = rng
        td = th.thrust_deduction
        if isinstance(td, schema.DeductionTable):
            angles, values = [math.radians(a) for a in td.azimuth_deg], list(td.value)
        else:
            angles, values = [0.0], [float(td)]
        row[mv.T_NTD] = len(angles)
        row[mv.T_TD0:mv.T_TD0 + len(angles)] = angles
        row[mv.T_TD0 + mv.MAX_TD:mv.T_TD0 + mv.MAX_TD + len(values)] = values
        row[mv.T_INTER] = 1.0 if interaction else 0.0
        rows.append(row)
        cfgs.append({"name": th.name if th.name is not None else f"thruster{i}",
                     "rated_rps": th.rated_rpm / 60.0, "full_360": th.full_360, "azimuth_range": rng,
                     "reversible": th.reversible})
    return rows, cfgs


def _steering_and_rudders(hp: np.ndarray, ship: schema.DisplacementShip, props: List[np.ndarray]):
    """steering: (S. D. Yoon Eq 10 gear) and rudders: (Eq 7-8 rows). Returns the rows and the
    largest steering angle, rad."""
    max_steer = math.radians(35.0)
    hp[mv.H_TE], hp[mv.H_MAXRATE] = 1.0, 1.0
    if ship.steering is not None:
        max_steer = math.radians(ship.steering.max_angle_deg)
        hp[mv.H_TE] = ship.steering.time_constant
        hp[mv.H_MAXRATE] = math.radians(ship.steering.max_rate_deg_s)
    ruds: List[np.ndarray] = []
    for r in ship.rudders or []:
        row = np.zeros(mv.NRUD)
        row[mv.R_X], row[mv.R_Y], row[mv.R_Z] = r.position
        lam = r.aspect_ratio
        height = r.height if r.height is not None else math.sqrt(lam * r.area)
        row[mv.R_AREA] = r.area
        row[mv.R_FALPHA] = 6.13 * lam / (lam + 2.25)     # Fujii, S. D. Yoon Eq 8
        if r.propeller is None:
            row[mv.R_PROP] = -1
            row[mv.R_ETA] = 0.0
        else:
            row[mv.R_PROP] = r.propeller
            row[mv.R_ETA] = props[r.propeller][mv.P_D] / height
        row[mv.R_AH] = r.a_H
        row[mv.R_XH] = r.x_H
        row[mv.R_TR] = r.t_R
        row[mv.R_WR0] = r.wake_fraction
        row[mv.R_LR] = r.l_R
        row[mv.R_KAPPA0] = r.kappa_factor
        ruds.append(row)
    hp[mv.H_NRUD] = len(ruds)
    return ruds, max_steer


def _anchor_section(hp: np.ndarray, ship: schema.DisplacementShip) -> Optional[dict]:
    """anchor: (S. D. Yoon Eq 5-6). Returns the let-go / heave-up timing and side, or None."""
    a = ship.anchor
    if a is None:
        return None
    hp[mv.H_ANC_LW] = a.holding_coefficient * a.weight_in_water
    hp[mv.H_ANC_LA] = a.moment_lever
    hp[mv.H_ANC_UEPS] = a.speed_regularisation
    hp[mv.H_ANC_RON] = a.turning_threshold
    hp[mv.H_ANC_VUCAP] = a.max_drift_ratio
    hp[mv.H_ANC_UREF] = a.turning_fade_speed
    sides = {"auto": 0.0, "port": 1.0, "starboard": -1.0}
    return {"let_go_time": a.let_go_time, "heave_up_time": a.heave_up_time, "side": sides[a.side],
            "holding_force": a.holding_coefficient * a.weight_in_water, "chain_out": a.chain_out,
            "chain_weight": a.chain_weight, "hawse_height": a.hawse_height}


def _towline_section(hp: np.ndarray, ship: schema.DisplacementShip, table_v: np.ndarray,
                     table_f: np.ndarray) -> None:
    """towline_simple: (Yun & Kim Eq 3)."""
    t = ship.towline_simple
    if t is None:
        return
    hp[mv.H_TOW_ON] = 1.0 if t.enabled else 0.0
    if t.force == "resistance":
        # the paper: X(u_c), the straight-running resistance at the reference speed u_c
        fval = -mv._interp_resistance.py_func(t.reference_speed, table_v, table_f)
    else:
        fval = t.force
    hp[mv.H_TOW_F] = fval
    hp[mv.H_TOW_X] = t.lever if t.lever is not None else 0.5 * ship.hull.length
    hp[mv.H_TOW_DRIFT] = t.drift_sign
    hp[mv.H_TOW_RATE] = math.radians(t.gamma_rate_deg_s)
    hp[mv.H_TOW_MAX] = math.radians(t.gamma_max_deg)
