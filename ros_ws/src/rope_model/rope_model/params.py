"""Rope parameters (Yoon, Lee, Park, Kim 2012, Table 1) and their YAML loader.

All values are SI. Paper units are converted in the YAML comments / here, once. Files are
checked against the schema in schema.py (required keys, physical ranges, unknown and
duplicate keys); errors name the file, the key and what was expected, e.g.
``table1.yaml: key 'diameter': expected a number in [0.001, 0.5] m, got -1.0``.
"""
from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field

import numpy as np

from sim_math.data_files import package_data_dir

from .schema import (RopeFile, RopeParamsError, check_breaking_strain, check_density,
                     read_yaml_mapping, validate_file)

G0 = 9.80665  # m/s^2, standard gravity: kgf -> N and tf -> N (Table 1)
TONNE_FORCE = 1000.0 * G0  # N per tf (Table 1 "16 ton" breaking strength)
KNOT = 1852.0 / 3600.0  # m/s per knot (section 4.4-4.6 speeds)

__all__ = ["G0", "KNOT", "TONNE_FORCE", "RopeParams", "RopeParamsError", "SeabedParams", "WinchParams",
           "load_rope_params", "default_rope_path", "shipped_rope_file", "finite_vec3"]


@dataclass(frozen=True)
class SeabedParams:
    """Seabed contact of the rope (the rope file's optional ``seabed:`` mapping; the seabed
    itself, its depth per element, comes from RopeChain.set_environment).

    MoorDyn's seabed model: a normal spring-damper per unit contact area (diameter x
    length), kBot = 3.0e6 Pa/m and cBot = 3.0e5 Pa s/m are MoorDyn's defaults (MoorDyn
    documentation, input file options kBot, cBot). Coulomb friction along and across the
    rope axis as MoorDyn-F's mu_kA / mu_kT (whose defaults are 0, friction off): here the
    dynamic friction coefficient of wire rope on the seabed, 0.25, of DNV-OS-E301 (Position
    mooring, the friction coefficient table of Ch.2: wire rope static 0.6 / dynamic 0.25,
    chain 1.0 / 0.7), both ways. Friction is regularised linearly below ``slip_speed``
    (MoorDyn's saturated damping min(mu N, c |v|) with c = mu N / slip_speed): a rope held by
    friction creeps at most at that speed.
    """

    stiffness: float = 3.0e6  # Pa/m (kBot)
    damping: float = 3.0e5  # Pa s/m (cBot)
    friction_axial: float = 0.25  # - (DNV-OS-E301 wire rope, dynamic)
    friction_transverse: float = 0.25  # -
    slip_speed: float = 0.01  # m/s


WINCH_MODES = ("speed", "hold", "constant_tension")


@dataclass(frozen=True)
class WinchParams:
    """The winch at end a (the rope file's optional ``winch:`` mapping; README "Winch").

    mode: the mode at the start, ``speed`` (the pay-out rate order, 0 = drum locked),
    ``hold`` (brake on: the drum is held while the drum tension T <= brake_load; above it
    the brake slips and pays out at v = min(gain (T - brake_load), winch_max_payout_speed),
    i.e. it resists with brake_load + v / gain: a Coulomb brake regularised by a steep
    viscous slope) or ``constant_tension`` (render / recover: pays out at
    min(gain (T - set_tension), winch_max_payout_speed) above set_tension, heaves in at
    min(gain (recover_tension - T), winch_max_heave_speed) below recover_tension, holds in
    between). None = the default: set_tension 0.5 breaking_load, recover_tension 0.2
    set_tension, brake_load 0.8 breaking_load (the brake slips before the line parts), gain
    winch_max_payout_speed / (0.1 breaking_load) (full speed at an error of a tenth of the
    breaking load). These are choices, not a source's figures."""

    mode: str = "speed"
    set_tension: float | None = None  # N
    recover_tension: float | None = None  # N
    brake_load: float | None = None  # N
    gain: float | None = None  # m/s per N

    def resolved(self, breaking_load: float, max_payout_speed: float) -> dict:
        """The settings with the defaults filled in: mode, set_tension, recover_tension,
        brake_load (N) and gain (m/s per N)."""
        ts = self.set_tension if self.set_tension is not None else 0.5 * breaking_load
        tr = self.recover_tension if self.recover_tension is not None else 0.2 * ts
        tb = self.brake_load if self.brake_load is not None else 0.8 * breaking_load
        g = self.gain if self.gain is not None else max_payout_speed / (0.1 * breaking_load)
        return dict(mode=self.mode, set_tension=float(ts), recover_tension=float(tr),
                    brake_load=float(tb), gain=float(g))


@dataclass(frozen=True)
class RopeParams:
    """Physical rope description (Table 1 defaults) plus environment constants.

    ``axial_stiffness`` (EA, N) defaults to breaking_load / elongation_at_break:
    Table 1 gives 16 tf at 15 % elongation, a linear rope then has EA = 1.046e6 N.
    """

    length: float = 100.0  # m, total rope (deployed + on the winch)
    diameter: float = 0.05  # m
    mass_per_length: float = 1.725  # kg/m (Table 1: weight 1.725 kgf/m)
    breaking_load: float = 16.0 * TONNE_FORCE  # N (Table 1: 16 tf)
    elongation_at_break: float = 0.15  # - (Table 1: 15 %)
    axial_stiffness: float | None = None  # N (EA); None -> breaking_load/elongation
    drag_normal: float = 1.2  # C_D, Eq (11)
    drag_tangential: float = 0.015  # C_f, Eq (11)
    # Eq (10) uses the diameter as reference width for both drags; MoorDyn and
    # Berteaux use the circumference (pi*D) for the tangential one -> factor pi.
    tangential_area_factor: float = 1.0
    added_mass_coefficient: float = 1.0  # Eq (9): m_y = m_z = rho*Vol
    # Eq (17) is ambiguous: the equation says transverse = axial/10 with
    # axial 0.5; the prose says transverse 0.5 and axial ten times larger.
    # Default = the equation (axial 0.5 matches Table 1's single "0.5").
    damping_ratio_axial: float = 0.5
    damping_ratio_transverse: float = 0.05
    damping_ratio_rotational: float = 0.5  # zeta_m, Eq (19)
    n_elements: int = 11  # Table 1
    min_length: float | None = None  # m, winch heave-in limit; None -> half an element
    water_density: float = 1025.0  # kg/m^3
    air_density: float = 1.225  # kg/m^3 (drag of the emerged part)
    gravity: float = G0  # m/s^2
    # winch at end a: pay-out / heave-in orders are clamped to these (schema.RopeFile)
    winch_max_payout_speed: float = 3.0  # m/s
    winch_max_heave_speed: float = 3.0  # m/s
    seabed: SeabedParams = field(default_factory=SeabedParams)  # seabed contact
    winch: WinchParams = field(default_factory=WinchParams)  # winch modes (end a)
    name: str = "rope"
    source: str = field(default="<defaults>", compare=False)

    @property
    def ea(self) -> float:
        if self.axial_stiffness is not None:
            return float(self.axial_stiffness)
        return self.breaking_load / self.elongation_at_break

    @property
    def radius(self) -> float:
        return 0.5 * self.diameter

    @property
    def nominal_element_length(self) -> float:
        return self.length / self.n_elements

    @property
    def min_deployed_length(self) -> float:
        if self.min_length is not None:
            return float(self.min_length)
        return 0.5 * self.nominal_element_length

    def replace(self, **changes) -> "RopeParams":
        """Copy with changes, validated like a file."""
        new = dataclasses.replace(self, **changes)
        _validate(new, new.source)
        return new


_POSITIVE = (
    "length", "diameter", "mass_per_length", "breaking_load", "elongation_at_break",
    "water_density",
)
_NONNEG = (
    "drag_normal", "drag_tangential", "tangential_area_factor", "added_mass_coefficient",
    "damping_ratio_axial", "damping_ratio_transverse", "damping_ratio_rotational",
    "air_density", "gravity",
)
_POSITIVE += ("winch_max_payout_speed", "winch_max_heave_speed")
_OPTIONAL_POSITIVE = ("axial_stiffness", "min_length")


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def check_numbers(p, bad, positive=(), nonneg=(), optional_positive=()) -> None:
    """Call bad(key, expected, got) for the first attribute of p outside its group's range."""
    for k in positive:
        v = getattr(p, k)
        if not _is_number(v) or v <= 0:
            bad(k, "a positive number", v)
    for k in nonneg:
        v = getattr(p, k)
        if not _is_number(v) or v < 0:
            bad(k, "a non-negative number", v)
    for k in optional_positive:
        v = getattr(p, k)
        if v is not None and (not _is_number(v) or v <= 0):
            bad(k, "a positive number or null", v)


def _validate(p: RopeParams, src: str) -> None:
    def bad(key, what, got):
        raise RopeParamsError(f"{src}: key '{key}': expected {what}, got {got!r}")

    check_numbers(p, bad, _POSITIVE, _NONNEG, _OPTIONAL_POSITIVE)
    if not isinstance(p.n_elements, int) or isinstance(p.n_elements, bool) or p.n_elements < 1:
        bad("n_elements", "an integer >= 1", p.n_elements)
    if p.elongation_at_break >= 1.0 and p.axial_stiffness is None:
        bad("elongation_at_break", "a strain below 1 (0.15 means 15 %)", p.elongation_at_break)
    if p.min_length is not None and p.min_length > p.length:
        bad("min_length", f"at most length ({p.length})", p.min_length)
    if not isinstance(p.name, str):
        bad("name", "a string", p.name)
    check_seabed(p.seabed, bad)
    check_winch(p, bad)


def check_winch(p, bad) -> None:
    """bad(key, expected, got) for a WinchParams out of range (mode, signs, finite, recover <=
    set tension)."""
    w = p.winch
    if not isinstance(w, WinchParams):
        bad("winch", "a WinchParams", w)
    if w.mode not in WINCH_MODES:
        bad("winch.mode", "one of " + ", ".join(repr(m) for m in WINCH_MODES), w.mode)
    for k, lo in (("set_tension", 0.0), ("recover_tension", None), ("brake_load", 0.0), ("gain", 0.0)):
        v = getattr(w, k)
        if v is None:
            continue
        if not _is_number(v) or v < 0 or (lo is not None and v <= lo):
            bad("winch." + k, "a positive number or null" if lo is not None else
                "a non-negative number or null", v)
    r = w.resolved(p.breaking_load, p.winch_max_payout_speed)
    if r["recover_tension"] > r["set_tension"]:
        bad("winch.recover_tension", f"at most winch.set_tension ({r['set_tension']:g} N)",
            r["recover_tension"])


_SEABED_POSITIVE = ("stiffness", "slip_speed")
_SEABED_NONNEG = ("damping", "friction_axial", "friction_transverse")


def check_seabed(sb, bad) -> None:
    """bad(key, expected, got) for a SeabedParams attribute out of range (signs, finite)."""
    if not isinstance(sb, SeabedParams):
        bad("seabed", "a SeabedParams", sb)

    def bad_sb(key, what, got):
        bad("seabed." + key, what, got)

    check_numbers(sb, bad_sb, _SEABED_POSITIVE, _SEABED_NONNEG)


_FIELDS = {f.name for f in dataclasses.fields(RopeParams)} - {"source"}


def read_mapping(path, what: str, error, empty_ok: bool = False):
    """(file name, dict) of a YAML parameter file (schema.read_yaml_mapping: duplicate keys,
    bad YAML and an empty file are errors naming the file; empty_ok is ignored)."""
    return read_yaml_mapping(path, what, error)


def load_rope_params(path: str | os.PathLike) -> RopeParams:
    """Read an element chain rope file (schema.RopeFile: the RopeParams field names, an
    optional ``model: element_chain``, the rope node's model selector).

    Raises FileNotFoundError (with the path) or RopeParamsError (file + key + expected).
    """
    src, data = read_yaml_mapping(path, "rope", RopeParamsError)
    f = validate_file(RopeFile, data, src, RopeParamsError)
    if f.axial_stiffness is not None:
        check_breaking_strain(src, "axial_stiffness", f.breaking_load, f.axial_stiffness)
    check_density(src, f.mass_per_length, f.diameter)
    if f.min_length is not None and f.min_length > f.length:
        raise RopeParamsError(f"{src}: key 'min_length': expected at most length ({f.length:g} m), "
                              f"got {f.min_length!r}")
    kw = {k: getattr(f, k) for k in _FIELDS if k in RopeFile.model_fields}
    kw["seabed"] = seabed_params(f.seabed)
    kw["winch"] = WinchParams() if f.winch is None else WinchParams(
        **{fl.name: getattr(f.winch, fl.name) for fl in dataclasses.fields(WinchParams)})
    p = RopeParams(**kw, source=src)
    _validate(p, src)
    return p


def seabed_params(sb) -> SeabedParams:
    """SeabedParams of a file's ``seabed:`` mapping (schema.SeabedFile or None: defaults)."""
    if sb is None:
        return SeabedParams()
    return SeabedParams(**{f.name: getattr(sb, f.name) for f in dataclasses.fields(SeabedParams)})


def shipped_rope_file(name: str) -> str:
    """Path of a rope file shipped in ropes/ (sim_math.data_files: the source tree, or the share)."""
    return os.path.join(package_data_dir("rope_model", "ropes"), name)


def default_rope_path() -> str:
    """Path of the shipped Table 1 rope (ropes/table1.yaml)."""
    return shipped_rope_file("table1.yaml")


def finite_vec3(v, what):
    """A copy of v as a float (3,) array; ValueError naming `what` if not 3 finite numbers."""
    a = np.asarray(v, dtype=float)
    if a.shape != (3,):
        raise ValueError(f"{what}: expected 3 numbers, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what}: must be finite, got {a.tolist()}")
    return a.copy()