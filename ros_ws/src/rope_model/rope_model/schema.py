"""Schemas of the rope files (element chain, ropes/table1.yaml) and cable files (fd cable,
ropes/cable_001.yaml), read with the one strict YAML reader (sim_math.input_files).

pydantic models with unknown keys forbidden and strict types (a string or a bool is not a
number, 11.0 is not an element count), the same approach as scenario_runner's scenario
format. Every error names the file, the key, what was expected and what was given, e.g.
``table1.yaml: key 'diameter': expected a number in [0.001, 0.5] m, got -1.0``. The ranges
are physical (comments say where each bound comes from): a value outside them is a slip of
units or of a digit, and would otherwise run as a silent absurdity (EA 1e15 N, water density
1e-9 kg/m^3).
"""
from __future__ import annotations

import math
import os
import typing
from typing import Literal, Optional

import annotated_types as at
from pydantic import BaseModel, ConfigDict, Field, ValidationError
from sim_math.input_files import YamlInputError, load_yaml

G0 = 9.80665  # m/s^2, standard gravity


class RopeParamsError(ValueError):
    """Bad rope or cable file / parameter; the message names the file and the key."""


def read_yaml_mapping(path, what: str, error=RopeParamsError):
    """(file name, dict) of a YAML parameter file that must hold a non-empty mapping. A missing
    file raises FileNotFoundError with the path; bad YAML, a duplicate key, an empty file or
    another top-level type raise error naming the file (and the line where YAML knows it)."""
    path = os.fspath(path)
    src = os.path.basename(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"{what} parameter file not found: {path}")
    try:
        data = load_yaml(path)  # the one strict reader: duplicate keys refused, 1e9 a number
    except YamlInputError as exc:
        where = f"line {exc.line}: " if exc.line is not None else ""
        if exc.duplicate_key is not None:
            raise error(f"{src}: {where}key '{exc.duplicate_key}': duplicate key (first given on line "
                        f"{exc.first_line})") from None
        raise error(f"{src}: {where}not valid YAML: {exc.problem}") from None
    if data is None:
        raise error(f"{src}: the file is empty: expected a mapping of {what} parameters")
    if not isinstance(data, dict):
        raise error(f"{src}: expected a mapping of {what} parameters, got {type(data).__name__}")
    return src, dict(data)


# ------------------------------------------------------------------ schema helpers
class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)


def num(default, lo, hi, unit="", *, lo_open=False):
    """A number field in [lo, hi] (lo_open: (lo, hi]); default ... = required."""
    low = {"gt": lo} if lo_open else {"ge": lo}
    return Field(default, le=hi, json_schema_extra={"unit": unit}, **low)


def _sub_schema(schema, key):
    """(schema, last key) of a dotted key into nested mappings ("seabed.stiffness")."""
    *path, last = key.split(".")
    for k in path:
        f = schema.model_fields.get(k)
        ann = f.annotation if f is not None else None
        if typing.get_origin(ann) is typing.Union:
            ann = [a for a in typing.get_args(ann) if a is not type(None)][0]
        if not (isinstance(ann, type) and issubclass(ann, BaseModel)):
            return schema, key
        schema = ann
    return schema, last


def _expected(schema, key) -> str:
    schema, key = _sub_schema(schema, key)
    f = schema.model_fields.get(key)
    if f is None:
        return "a known key"
    ann = f.annotation
    optional = False
    if typing.get_origin(ann) is typing.Union:
        args = [a for a in typing.get_args(ann) if a is not type(None)]
        optional, ann = True, args[0]
    if isinstance(ann, type) and issubclass(ann, BaseModel):
        text = "a mapping of " + ", ".join(ann.model_fields)
    elif typing.get_origin(ann) is Literal:
        text = "one of " + ", ".join(repr(a) for a in typing.get_args(ann))
    elif ann is bool:
        text = "true or false"
    elif ann is str:
        text = "a string"
    else:
        lo = hi = None
        lb = "["
        for m in f.metadata:
            if isinstance(m, at.Ge):
                lo = m.ge
            elif isinstance(m, at.Gt):
                lo, lb = m.gt, "("
            elif isinstance(m, at.Le):
                hi = m.le
        kind = "an integer" if ann is int else "a number"
        text = f"{kind} in {lb}{lo:g}, {hi:g}]" if lo is not None and hi is not None else kind
        unit = (f.json_schema_extra or {}).get("unit", "")
        if unit:
            text += f" {unit}"
    return text + (" or null" if optional else "")


def validate_file(schema, data: dict, src: str, error=RopeParamsError):
    """schema instance of data; error lists every bad key (values first, missing keys last)."""
    try:
        return schema.model_validate(data)
    except ValidationError as exc:
        lines = []
        for e in exc.errors():
            key = ".".join(str(p) for p in e["loc"] if isinstance(p, str)) or "(top)"
            if e["type"] == "extra_forbidden":
                known = ", ".join(sorted(_sub_schema(schema, key)[0].model_fields))
                lines.append((1, f"{src}: key '{key}': unknown key (misspelt? known: {known})"))
            elif e["type"] == "missing":
                lines.append((2, f"{src}: key '{key}': required key is missing (expected "
                                 f"{_expected(schema, key)})"))
            else:
                lines.append((0, f"{src}: key '{key}': expected {_expected(schema, key)}, "
                                 f"got {e.get('input')!r}"))
        seen = []
        for _, line in sorted(lines, key=lambda x: x[0]):
            if line not in seen:
                seen.append(line)
        raise error("\n".join(seen)) from None


def check_breaking_strain(src, key, breaking_load, ea, error=RopeParamsError):
    """breaking_load / EA is the strain at break of a linear rope: steel wire rope about
    0.01-0.02, HMPE 0.035, polyester 0.12-0.15, nylon 0.2-0.4 (Table 1: 0.15). Outside
    0.005-0.8 the pair is not a rope (EA 1e12 N with Table 1's 157 kN breaks at 1.6e-7)."""
    eps = breaking_load / ea
    if not 0.005 <= eps <= 0.8:
        raise error(f"{src}: key '{key}': breaking_load / {key} = {breaking_load:g} N / {ea:g} N "
                    f"= {eps:.3g} is not a rope's strain at break (expected 0.005..0.8)")


def check_density(src, mass_per_length, diameter, error=RopeParamsError):
    """Mass per metre over the nominal section pi d^2 / 4: from a floating fibre rope with its
    voids (polypropylene, about 500 kg/m^3) to solid steel (7850); Table 1 is 878 kg/m^3."""
    rho = mass_per_length / (0.25 * math.pi * diameter ** 2)
    if not 300.0 <= rho <= 9000.0:
        raise error(f"{src}: key 'mass_per_length': {mass_per_length:g} kg/m on a {diameter:g} m "
                    f"diameter is {rho:.4g} kg/m^3 over the section (expected 300..9000 kg/m^3: "
                    f"wrong unit or diameter?)")


# ------------------------------------------------------------------ the two file kinds
# Shared bounds. Towlines are tens of m to about 2 km (deep-sea tow wires); diameters 2 mm
# (a heaving line) to 0.5 m (the largest fibre hawsers are about 0.3 m). EA: a 200 mm steel
# wire rope has EA ~ 3e9 N (E ~ 100 GPa on its metallic area), 1e10 N leaves margin; 1e3 N is
# a rubber cord. Drag (Eq 11 / Park & Jung Eq 6): normal C_D of a cylinder 1.0-1.2, stranded
# ropes up to about 2; skin friction 0.01-0.03. Environment: water 1000 (fresh) .. 1025 (sea)
# kg/m^3, air 1.1 (40 degC) .. 1.42 (-30 degC), gravity 9.78-9.83 on the Earth's surface
# (bounds as the scenario format's environment).
LEN = (1.0, 1.0e4, "m")
DIAM = (0.001, 0.5, "m")
MASS = (0.001, 1000.0, "kg/m")
EA = (1.0e3, 1.0e10, "N")
RHO_W = (900.0, 1100.0, "kg/m^3")
GRAV = (9.0, 10.5, "m/s^2")


class SeabedFile(_Strict):
    """The optional ``seabed:`` mapping of a rope or cable file (params.SeabedParams: the
    defaults and their sources). Bounds: kBot from a soft mud (1e3 Pa/m) to rock (1e9; MoorDyn's
    default 3e6), cBot up to 1e8 Pa s/m, friction coefficients 0 (none) to 2 (chain dug into
    clay: lateral about 1-1.5), the regularising slip speed 0.1 mm/s to 1 m/s."""

    stiffness: float = num(3.0e6, 1.0e3, 1.0e9, "Pa/m")
    damping: float = num(3.0e5, 0.0, 1.0e8, "Pa s/m")
    friction_axial: float = num(0.25, 0.0, 2.0)
    friction_transverse: float = num(0.25, 0.0, 2.0)
    slip_speed: float = num(0.01, 1.0e-4, 1.0, "m/s")


WINCH_MODES = ("speed", "hold", "constant_tension")


class WinchFile(_Strict):
    """The optional ``winch:`` mapping of a rope file: the winch at end a (params.WinchParams:
    the defaults, the brake slip law and the render / recover controller). Tensions in N
    (null: a fraction of the breaking load, see params.WinchParams); the gain in m/s per N
    (null: winch_max_payout_speed at an error of a tenth of the breaking load)."""

    mode: Literal["speed", "hold", "constant_tension"] = "speed"
    set_tension: Optional[float] = num(None, 0.0, 1.0e8, "N", lo_open=True)
    recover_tension: Optional[float] = num(None, 0.0, 1.0e8, "N")  # 0: never heaves in
    brake_load: Optional[float] = num(None, 0.0, 2.0e8, "N", lo_open=True)
    gain: Optional[float] = num(None, 0.0, 1.0, "m/s per N", lo_open=True)


class RopeFile(_Strict):
    """Element chain rope file (Yoon, Lee, Park, Kim 2012; ropes/table1.yaml)."""

    model: Literal["element_chain"] = "element_chain"
    name: str = "rope"
    # required: the rope itself
    length: float = num(..., *LEN)
    diameter: float = num(..., *DIAM)
    mass_per_length: float = num(..., *MASS)
    breaking_load: float = num(..., 100.0, 1.0e8, "N")  # 100 N twine .. 100 MN (x3 the largest hawsers)
    elongation_at_break: float = num(..., 0.005, 0.8, "(strain)")  # see check_breaking_strain
    drag_normal: float = num(..., 0.0, 3.0)
    drag_tangential: float = num(..., 0.0, 0.5)
    # optional, with the Table 1 / paper defaults
    axial_stiffness: Optional[float] = num(None, *EA)  # null -> breaking_load / elongation
    tangential_area_factor: float = num(1.0, 0.0, 4.0)  # 1 (Eq 10) or pi (MoorDyn)
    added_mass_coefficient: float = num(1.0, 0.0, 2.0)  # cylinder: 1
    # Eq 17 ambiguity: the prose reading needs axial 5.0; 10 = far overdamped
    damping_ratio_axial: float = num(0.5, 0.0, 10.0)
    damping_ratio_transverse: float = num(0.05, 0.0, 10.0)
    damping_ratio_rotational: float = num(0.5, 0.0, 10.0)
    n_elements: int = num(11, 1, 2000)  # the rope node's own limit
    min_length: Optional[float] = num(None, 0.0, 1.0e4, "m", lo_open=True)
    water_density: float = num(1025.0, *RHO_W)
    air_density: float = num(1.225, 0.9, 1.5, "kg/m^3")
    gravity: float = num(G0, *GRAV)
    # winch at end a: largest pay-out / heave-in speeds; orders beyond are clamped. Towing
    # winches haul 0.3-1 m/s at full pull and run a light line at 2-3 m/s; 3.0 m/s keeps the
    # shipped scenarios (section 4.6 pays out at 5 kn = 2.5722 m/s). 10 m/s: no winch is faster.
    winch_max_payout_speed: float = num(3.0, 0.0, 10.0, "m/s", lo_open=True)
    winch_max_heave_speed: float = num(3.0, 0.0, 10.0, "m/s", lo_open=True)
    seabed: Optional[SeabedFile] = None  # null / absent: the defaults
    winch: Optional[WinchFile] = None  # null / absent: the defaults (params.WinchParams)


class CableFile(_Strict):
    """Finite-difference cable file (Park & Jung; ropes/cable_001.yaml)."""

    model: Literal["fd_cable"]
    name: str = "cable"
    length: float = num(..., *LEN)
    diameter: float = num(..., *DIAM)
    weight_in_water: float = num(..., 0.0, 1.0e4, "N/m")  # w0 of Eq 2; 200 mm steel: ~1.4e3
    youngs_modulus: float = num(..., 1.0e6, 3.0e11, "Pa")  # soft elastomer .. steel (2.1e11)
    drag_tangential: float = num(..., 0.0, 0.5)
    drag_normal: float = num(..., 0.0, 3.0)
    drag_binormal: float = num(..., 0.0, 3.0)
    n_nodes: int = num(7, 3, 2000)
    mass_per_length: Optional[float] = num(None, *MASS)  # null -> w0/g + rho A
    axial_stiffness: Optional[float] = num(None, *EA)  # null -> E A
    # null -> E pi d^4 / 64; 1e8 N m^2 = a solid 0.3 m steel bar, stiffer than any cable
    bending_stiffness: Optional[float] = num(None, 0.0, 1.0e8, "N m^2", lo_open=True)
    added_mass_coefficient: float = num(1.0, 0.0, 2.0)
    added_mass_full_acceleration: bool = True
    water_density: float = num(1025.0, *RHO_W)
    gravity: float = num(G0, *GRAV)
    current_along_heading: float = num(-1.0, -10.0, 10.0, "m/s")  # the rope node's current range
    tow_speed: float = num(1.0, -20.0, 20.0, "m/s")
    time_weight: float = num(0.5, 0.5, 1.0)  # Eq 13: 0.5 centred .. 1 fully implicit
    newton_tol: float = num(1.0e-9, 0.0, 1.0e-2, lo_open=True)
    newton_max_iter: int = num(25, 1, 200)
    max_halvings: int = num(4, 0, 12)
    rebase_angle: float = num(0.7, 0.0, 1.4, "rad", lo_open=True)  # theta = pi/2 is singular
