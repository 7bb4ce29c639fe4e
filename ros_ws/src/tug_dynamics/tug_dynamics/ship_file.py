"""Ship files: YAML descriptions of vessels; ``load_ship`` builds the model a file names.

The key ``model:`` selects the class:
  displacement   tug_dynamics.maneuvering.ManeuveringVessel (this module builds it)
  planing_6dof   tug_dynamics.planing.PlaningHull.from_config(cfg, source, name, initial_state)

Every error names the file and the dotted key. Unknown keys are errors (typos would
otherwise silently fall back to defaults). ``estimated:`` maps dotted keys to the method
used to estimate them; each listed key must exist in the file. Schema: README.md.
"""
from __future__ import annotations

import copy
import glob
import math
import os
from typing import Any, List, Optional

import numpy as np
import yaml

from . import maneuvering as mv
from .vessel import Vessel, VesselState

SHIPS_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "ships")
G = 9.80665


class ShipFileError(ValueError):
    """A ship file that cannot be used; the message names the file and the key."""


def ships_dir() -> str:
    """The ships directory: the source tree's ships/, else the installed share/tug_dynamics/ships."""
    if os.path.isdir(SHIPS_DIR):
        return SHIPS_DIR
    try:
        from ament_index_python.packages import get_package_share_directory  # optional, ROS installs
        return os.path.join(get_package_share_directory("tug_dynamics"), "ships")
    except Exception:  # noqa: BLE001 - no ROS: fall back to the source layout
        return SHIPS_DIR


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


class _Section:
    """Typed access to one mapping of the file; records keys used to find unknown ones."""

    def __init__(self, src: str, path: str, data: Any):
        self.src, self.path = src, path
        if not isinstance(data, dict):
            raise ShipFileError(f"{src}: key '{path}': expected a mapping, got {type(data).__name__}")
        self.data = data
        self.used = set()

    def key(self, k: str) -> str:
        return f"{self.path}.{k}" if self.path else k

    def err(self, k: str, msg: str) -> ShipFileError:
        return ShipFileError(f"{self.src}: key '{self.key(k)}': {msg}")

    def has(self, k: str) -> bool:
        return k in self.data

    def raw(self, k: str, default: Any = ...) -> Any:
        self.used.add(k)
        if k not in self.data:
            if default is ...:
                raise self.err(k, "required key is missing")
            return default
        return self.data[k]

    def num(self, k: str, default: Any = ..., lo: float = -math.inf, hi: float = math.inf,
            positive: bool = False) -> float:
        v = self.raw(k, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.err(k, f"expected a number, got {v!r}")
        v = float(v)
        if not math.isfinite(v):
            raise self.err(k, f"{v!r} is not finite")
        if positive and v <= 0.0:
            raise self.err(k, f"must be > 0, got {v:g}")
        if not lo <= v <= hi:
            raise self.err(k, f"must be in [{lo:g}, {hi:g}], got {v:g}")
        return v

    def vec(self, k: str, n: Optional[int] = None, default: Any = ...) -> np.ndarray:
        v = self.raw(k, default)
        try:
            a = np.asarray(v, float).reshape(-1)
        except (TypeError, ValueError):
            raise self.err(k, f"expected a list of numbers, got {v!r}") from None
        if n is not None and a.size != n:
            raise self.err(k, f"expected {n} numbers, got {a.size}")
        if not np.all(np.isfinite(a)):
            raise self.err(k, "contains a non-finite number")
        return a

    def sub(self, k: str, default: Any = ...) -> Optional["_Section"]:
        v = self.raw(k, default)
        if v is None:
            return None
        return _Section(self.src, self.key(k), v)

    def finish(self) -> None:
        extra = sorted(set(self.data) - self.used)
        if extra:
            raise self.err(extra[0], f"unknown key (known here: {sorted(self.used)})")


def _read_yaml(path: str) -> dict:
    try:
        with open(path, "r", encoding="utf-8") as fh:
            cfg = yaml.safe_load(fh)
    except OSError as exc:
        raise ShipFileError(f"{path}: cannot read: {exc}") from None
    except yaml.YAMLError as exc:
        raise ShipFileError(f"{path}: not valid YAML: {exc}") from None
    if not isinstance(cfg, dict):
        raise ShipFileError(f"{path}: top level must be a mapping")
    return cfg


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


def load_ship(path: str, name: Optional[str] = None, initial_state: Optional[VesselState] = None,
              *, overrides: Optional[dict] = None) -> Vessel:
    """Build the vessel a ship file describes.

    path: a file path, or a bare file name looked up in ships_dir().
    name: vessel name (default: the file's ``name``). initial_state: default at rest at the origin.
    overrides: nested dict merged over the file before parsing (tests, scenario variants).
    """
    if not os.path.exists(path) and not os.path.isabs(path):
        cand = os.path.join(ships_dir(), path)
        if os.path.exists(cand):
            path = cand
    src = os.path.abspath(path)
    cfg = _read_yaml(src)
    if overrides:
        cfg = _deep_merge(cfg, overrides)
    model = cfg.get("model")
    if model is None:
        raise ShipFileError(f"{src}: key 'model': required key is missing (displacement | planing_6dof)")
    if model == "planing_6dof":
        from .planing import PlaningHull  # lazy: written separately
        return PlaningHull.from_config(cfg, src, name, initial_state)
    if model != "displacement":
        raise ShipFileError(f"{src}: key 'model': unknown model {model!r} (displacement | planing_6dof)")
    vessel = _build_displacement(src, cfg, name, initial_state)
    if not overrides:      # an override may remove sections the estimates refer to
        _check_estimated(src, cfg)
    return vessel


_POLY_KEYS = ["Xvv", "Xrr", "Xvr", "Yv", "Yvav", "Yr", "Yrar", "Yvrr", "Yrvv",
              "Nv", "Nvav", "Nr", "Nrar", "Nvrr", "Nrvv"]
_LOW_KEYS = ["Xuu", "Xvr", "Yv", "Yr", "Yvv", "Yvr", "Yrr", "Nv", "Nr", "Nvvr", "Nvrr", "Nrr"]


def _build_displacement(src: str, cfg: dict, name: Optional[str], initial_state) -> mv.ManeuveringVessel:
    top = _Section(src, "", cfg)
    for k in ("model", "description", "sources", "estimated", "notes"):
        top.raw(k, None)
    file_name = top.raw("name", None)  # always read, so it never counts as unknown
    vname = name or str(file_name)
    rho = top.num("water_density", positive=True)
    hp = np.zeros(mv.NHULL)
    hp[mv.H_RHO] = rho

    # ---- hull ----
    h = top.sub("hull")
    L = h.num("length", positive=True)
    B = h.num("beam", positive=True)
    T = h.num("draft", positive=True)
    m = h.num("mass", positive=True)
    xg = h.num("x_g", 0.0)
    kzz = h.num("yaw_radius_of_gyration", positive=True)
    form = h.raw("form")
    enabled = bool(h.raw("enabled", True))
    hp[mv.H_L], hp[mv.H_T], hp[mv.H_M], hp[mv.H_XG] = L, T, m, xg
    d = h.sub("derivatives")
    if form == "polynomial":
        keys = _POLY_KEYS
        hp[mv.H_FORM] = mv.FORM_POLY
        q3 = 0.5 * rho * L ** 3
        mx = -d.num("Xudot") * q3
        my = -d.num("Yvdot") * q3
        m_yr = -d.num("Yrdot") * q3 * L
        m_nv = -d.num("Nvdot") * q3 * L
        jz = -d.num("Nrdot") * q3 * L * L
        hp[mv.H_MMG_CORIOLIS] = 0.0
    elif form == "lowspeed":
        keys = _LOW_KEYS
        hp[mv.H_FORM] = mv.FORM_LOWSPEED
        am = h.sub("added_mass")
        mx = am.num("mx_over_m", lo=0.0) * m
        my = am.num("my_over_m", lo=0.0) * m
        jz = am.num("Jz_over_mL2", lo=0.0) * m * L * L
        m_yr = m_nv = 0.0
        am.finish()
        hp[mv.H_MMG_CORIOLIS] = 1.0
    else:
        raise h.err("form", f"unknown hull form {form!r} (polynomial | lowspeed)")
    for i, k in enumerate(keys):
        hp[mv.H_C0 + i] = d.num(k)
    d.finish()
    res = h.sub("resistance", None)
    if res is not None:
        rv = res.vec("speed")
        rf = res.vec("force")
        if rv.size != rf.size or rv.size == 0 or np.any(np.diff(rv) <= 0) or rv[0] < 0 or np.any(rf < 0):
            raise res.err("speed", "speed and force must be equal-length, speed increasing >= 0, force >= 0")
        res.finish()
    else:
        rv = rf = np.zeros(0)
    h.finish()
    table_v, table_f = rv, rf          # kept for the towline's X(u_c) even with the hull off
    if not enabled:
        # hull forces off: no damping, no added mass (a pure rigid body)
        hp[mv.H_FORM] = mv.FORM_NONE
        mx = my = m_yr = m_nv = jz = 0.0
        rv = rf = np.zeros(0)
    hp[mv.H_MX], hp[mv.H_MY] = mx, my

    # ---- roll ----
    rsec = top.sub("roll", None)
    roll_cfg = None
    M = np.zeros((4, 4))
    M[0, 0] = m + mx
    M[1, 1] = m + my
    M[1, 2] = m * xg + m_yr
    M[2, 1] = m * xg + m_nv
    M[2, 2] = m * kzz ** 2 + m * xg ** 2 + jz
    hp[mv.H_ZH] = -0.5 * T
    if rsec is not None:
        gm = rsec.num("gm", positive=True)
        kxx = rsec.num("radius_of_gyration", positive=True)
        jx = rsec.num("added_inertia_ratio", lo=0.0) * m * kxx ** 2
        zg = rsec.num("z_g")
        zeta = rsec.num("damping_ratio", lo=0.0)
        hp[mv.H_ZH] = rsec.num("z_lateral_resistance", hi=0.0)
        fb = rsec.num("freeboard", positive=True)
        bm = rsec.num("bm", positive=True)
        thr = rsec.num("girting_threshold", positive=True)
        rsec.finish()
        ix = m * kxx ** 2 + m * zg ** 2 + jx
        M[1, 3] = M[3, 1] = -m * zg
        M[3, 3] = ix
        hp[mv.H_ROLL], hp[mv.H_ZG] = 1.0, zg
        hp[mv.H_GMW] = m * G * gm
        hp[mv.H_KP] = 2.0 * zeta * math.sqrt(ix * m * G * gm)
        phi_de = math.atan2(fb, 0.5 * B)
        gz = math.sin(phi_de) * (gm + 0.5 * bm * math.tan(phi_de) ** 2)   # wall-sided, deck edge
        roll_cfg = {"gm": gm, "deck_edge_angle": phi_de, "max_righting_moment": m * G * gz,
                    "girting_threshold": thr, "z_lateral_resistance": hp[mv.H_ZH]}
    else:
        M[3, 3] = 1.0

    # ---- engine, propellers ----
    props: List[np.ndarray] = []
    rated_rps = 0.0
    esec = top.sub("engine", None)
    hp[mv.H_TN] = 1.0
    if esec is not None:
        rated_rps = esec.num("rated_rpm", positive=True) / 60.0
        hp[mv.H_TN] = esec.num("time_constant", positive=True)
        esec.finish()
    plist = top.raw("propellers", []) or []
    if plist and esec is None:
        raise top.err("engine", "propellers need an 'engine' section (rated_rpm, time_constant)")
    for i, pd in enumerate(plist):
        p = _Section(src, f"propellers.{i}", pd)
        row = np.zeros(mv.NPROP)
        pos = p.vec("position", 3)
        row[mv.P_X], row[mv.P_Y], row[mv.P_Z] = pos
        row[mv.P_D] = p.num("diameter", positive=True)
        row[mv.P_PITCH] = p.num("pitch_ratio", positive=True) * row[mv.P_D]
        row[mv.P_C1], row[mv.P_C2], row[mv.P_C3] = p.vec("kt", 3)
        row[mv.P_WP0] = p.num("wake_fraction", lo=0.0, hi=0.9)
        row[mv.P_T] = p.num("thrust_deduction", lo=0.0, hi=0.9)
        row[mv.P_AST] = p.num("astern_factor", lo=0.0, hi=1.5)
        p.finish()
        props.append(row)
    if len(props) > 4:
        raise top.err("propellers", "at most 4 propellers")
    hp[mv.H_NPROP] = len(props)

    # ---- steering gear, rudders ----
    ssec = top.sub("steering", None)
    max_steer = math.radians(35.0)
    hp[mv.H_TE], hp[mv.H_MAXRATE] = 1.0, 1.0
    if ssec is not None:
        max_steer = math.radians(ssec.num("max_angle_deg", positive=True, hi=180.0))
        hp[mv.H_TE] = ssec.num("time_constant", positive=True)
        hp[mv.H_MAXRATE] = math.radians(ssec.num("max_rate_deg_s", positive=True))
        ssec.finish()
    ruds: List[np.ndarray] = []
    for i, rdict in enumerate(top.raw("rudders", []) or []):
        r = _Section(src, f"rudders.{i}", rdict)
        row = np.zeros(mv.NRUD)
        pos = r.vec("position", 3)
        row[mv.R_X], row[mv.R_Y], row[mv.R_Z] = pos
        area = r.num("area", positive=True)
        lam = r.num("aspect_ratio", positive=True)
        height = r.num("height", math.sqrt(lam * area), positive=True)
        row[mv.R_AREA] = area
        row[mv.R_FALPHA] = 6.13 * lam / (lam + 2.25)     # Fujii, seed 003 Eq 8
        pidx = r.raw("propeller", None)
        if pidx is None:
            row[mv.R_PROP] = -1
            row[mv.R_ETA] = 0.0
        else:
            if not isinstance(pidx, int) or not 0 <= pidx < len(props):
                raise r.err("propeller", f"must be an index into propellers (0..{len(props) - 1}) or null")
            row[mv.R_PROP] = pidx
            row[mv.R_ETA] = props[pidx][mv.P_D] / height
        row[mv.R_AH] = r.num("a_H")
        row[mv.R_XH] = r.num("x_H")
        row[mv.R_TR] = r.num("t_R", lo=0.0, hi=1.0)
        row[mv.R_WR0] = r.num("wake_fraction", lo=0.0, hi=0.9)
        row[mv.R_LR] = r.num("l_R")
        row[mv.R_KAPPA0] = r.num("kappa_factor", 0.6, positive=True)
        r.finish()
        ruds.append(row)
    if len(ruds) > 4:
        raise top.err("rudders", "at most 4 rudders")
    if ruds and ssec is None:
        raise top.err("steering", "rudders need a 'steering' section")
    hp[mv.H_NRUD] = len(ruds)

    # ---- anchor (seed 003 Eq 5-6) ----
    asec = top.sub("anchor", None)
    anchor_cfg = None
    if asec is not None:
        lam_a = asec.num("holding_coefficient", lo=0.0)
        wiw = asec.num("weight_in_water", positive=True)
        hp[mv.H_ANC_LW] = lam_a * wiw
        hp[mv.H_ANC_LA] = asec.num("moment_lever", lo=0.0)
        hp[mv.H_ANC_UEPS] = asec.num("speed_regularisation", 0.05, positive=True)
        hp[mv.H_ANC_RON] = asec.num("turning_threshold", 0.05, positive=True)
        hp[mv.H_ANC_VUCAP] = asec.num("max_drift_ratio", 1.0, positive=True)
        hp[mv.H_ANC_UREF] = asec.num("turning_fade_speed", 0.5, positive=True)
        side = asec.raw("side", "auto")
        sides = {"auto": 0.0, "port": 1.0, "starboard": -1.0}
        if side not in sides:
            raise asec.err("side", f"must be one of {sorted(sides)}, got {side!r}")
        anchor_cfg = {"let_go_time": asec.num("let_go_time", lo=0.0),
                      "heave_up_time": asec.num("heave_up_time", positive=True),
                      "side": sides[side]}
        asec.finish()

    # ---- seed 002 Eq 3 simple towline ----
    tsec = top.sub("towline_simple", None)
    if tsec is not None:
        hp[mv.H_TOW_ON] = 1.0 if bool(tsec.raw("enabled", False)) else 0.0
        if tsec.raw("force", "resistance") == "resistance":
            # the paper: X(u_c), the straight-running resistance at the reference speed u_c
            uc = tsec.num("reference_speed", positive=True)
            if table_v.size == 0:
                raise tsec.err("force", "'resistance' needs hull.resistance")
            fval = -mv._interp_resistance.py_func(uc, table_v, table_f)
        else:
            fval = tsec.num("force", positive=True)
        hp[mv.H_TOW_F] = fval
        hp[mv.H_TOW_X] = tsec.num("lever", 0.5 * L)
        hp[mv.H_TOW_DRIFT] = tsec.num("drift_sign", 1.0, lo=-1.0, hi=1.0)
        hp[mv.H_TOW_RATE] = math.radians(tsec.num("gamma_rate_deg_s", positive=True))
        hp[mv.H_TOW_MAX] = math.radians(tsec.num("gamma_max_deg", lo=-90.0, hi=90.0))
        tsec.finish()

    # ---- attachments, integration, current ----
    att = {}
    asub = top.sub("attachments", None)
    if asub is not None:
        for k in list(asub.data):
            att[str(k)] = asub.vec(k, 3)
        asub.finish()
    isec = top.sub("integration", None)
    hmax = 0.1 * math.sqrt(L / G)
    if isec is not None:
        hmax = isec.num("max_substep", positive=True)
        isec.finish()
    cur = top.vec("current", 2, [0.0, 0.0])
    top.finish()

    return mv.ManeuveringVessel(
        vname, hp, np.array(props) if props else np.zeros((0, mv.NPROP)),
        np.array(ruds) if ruds else np.zeros((0, mv.NRUD)), rv, rf, M,
        {"max_steering": max_steer, "rated_rps": rated_rps}, att, anchor=anchor_cfg, roll=roll_cfg,
        hmax=hmax, initial_state=initial_state, current=(cur[0], cur[1]), source=src)
