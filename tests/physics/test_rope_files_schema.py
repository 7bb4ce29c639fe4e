"""Rope and cable files are checked against a schema (rope_model/schema.py).

A corpus of broken files, each written to tmp_path: every one must be refused with a
RopeParamsError (FdCableParamsError is one) naming the file, the offending key and what was
expected; the shipped files still load."""
import math
import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src", "rope_model"))

from rope_model import RopeParamsError, default_rope_path, load_rope_params  # noqa: E402
from rope_model.fd_cable import FdCableParamsError, default_cable_path, load_cable_params  # noqa: E402
from rope_model.models import load_params, rope_file_model  # noqa: E402

ROPE_TEXT = open(default_rope_path()).read()
CABLE_TEXT = open(default_cable_path()).read()


def _with(text, line):
    """text with the line of line's key replaced by line (appended if new; None drops it)."""
    key = line.split(":")[0]
    out, done = [], False
    for old in text.splitlines():
        if old.split(":")[0] == key:
            done = True
            if ":" in line and line.split(":", 1)[1].strip() != "DROP":
                out.append(line)
        else:
            out.append(old)
    if not done:
        out.append(line)
    return "\n".join(out) + "\n"


# (name, text, key named in the message (or None), text the message must contain)
ROPE_CASES = [
    ("empty", "", None, "the file is empty"),
    ("comments_only", "# nothing here\n", None, "the file is empty"),
    ("missing_diameter", _with(ROPE_TEXT, "diameter: DROP"), "diameter", "required key is missing"),
    ("missing_breaking_load", _with(ROPE_TEXT, "breaking_load: DROP"), "breaking_load",
     "required key is missing"),
    ("unknown_key", _with(ROPE_TEXT, "colour: orange"), "colour", "unknown key"),
    ("duplicate_key", ROPE_TEXT + "length: 200.0\n", "length", "duplicate key (first given on line 3)"),
    ("invalid_yaml", _with(ROPE_TEXT, "diameter: [0.05"), None, "not valid YAML"),
    ("nan", _with(ROPE_TEXT, "breaking_load: .nan"), "breaking_load", "got nan"),
    ("inf", _with(ROPE_TEXT, "length: .inf"), "length", "got inf"),
    ("negative_length", _with(ROPE_TEXT, "length: -100.0"), "length", "[1, 10000] m, got -100.0"),
    ("zero_length", _with(ROPE_TEXT, "length: 0"), "length", "[1, 10000] m, got 0"),
    ("ea_1e15", _with(ROPE_TEXT, "axial_stiffness: 1.0e+15"), "axial_stiffness", "[1000, 1e+10] N"),
    ("ea_1e12", _with(ROPE_TEXT, "axial_stiffness: 1e12"), "axial_stiffness", "[1000, 1e+10] N"),
    # in range, but 157 kN on EA 1e9 N breaks at 0.016 % strain: not a rope
    ("ea_vs_breaking_load", _with(ROPE_TEXT, "axial_stiffness: 1.0e+9"), "axial_stiffness",
     "not a rope's strain at break"),
    ("water_density_1e-9", _with(ROPE_TEXT, "water_density: 1.0e-9"), "water_density",
     "[900, 1100] kg/m^3"),
    ("air_density", _with(ROPE_TEXT, "air_density: 1025.0"), "air_density", "[0.9, 1.5]"),
    ("gravity", _with(ROPE_TEXT, "gravity: 98.0665"), "gravity", "[9, 10.5] m/s^2"),
    ("mass_1e30", _with(ROPE_TEXT, "mass_per_length: 1.0e+30"), "mass_per_length", "kg/m"),
    # 1.725 t/m on a 5 cm rope: 879,000 kg/m^3 (kg and t mixed up)
    ("mass_vs_diameter", _with(ROPE_TEXT, "mass_per_length: 1725.0"), "mass_per_length", "kg/m"),
    ("density_cross_check", _with(ROPE_TEXT, "mass_per_length: 100.0"), "mass_per_length",
     "kg/m^3 over the section"),
    ("string_for_number", _with(ROPE_TEXT, "diameter: fifty mm"), "diameter", "got 'fifty mm'"),
    ("quoted_number", _with(ROPE_TEXT, 'diameter: "0.05"'), "diameter", "got '0.05'"),
    ("bool_for_number", _with(ROPE_TEXT, "drag_normal: true"), "drag_normal", "got True"),
    ("n_elements_0", _with(ROPE_TEXT, "n_elements: 0"), "n_elements", "an integer in [1, 2000]"),
    ("n_elements_float", _with(ROPE_TEXT, "n_elements: 11.0"), "n_elements", "an integer"),
    ("elongation_15", _with(ROPE_TEXT, "elongation_at_break: 15"), "elongation_at_break", "[0.005, 0.8]"),
    ("diameter_in_mm", _with(ROPE_TEXT, "diameter: 50"), "diameter", "[0.001, 0.5] m"),
    ("min_length_above_length", _with(ROPE_TEXT, "min_length: 150.0"), "min_length", "at most length"),
    ("damping_negative", _with(ROPE_TEXT, "damping_ratio_axial: -0.5"), "damping_ratio_axial", "[0, 10]"),
    ("winch_speed_zero", _with(ROPE_TEXT, "winch_max_payout_speed: 0"), "winch_max_payout_speed",
     "(0, 10] m/s"),
    ("winch_speed_huge", _with(ROPE_TEXT, "winch_max_heave_speed: 1.0e+6"), "winch_max_heave_speed",
     "(0, 10] m/s"),
    ("wrong_model", _with(ROPE_TEXT, "model: fd_kable"), "model", "fd_cable"),
    ("list_top_level", "- 1\n- 2\n", None, "expected a mapping"),
]


@pytest.mark.parametrize("name,text,key,what", ROPE_CASES, ids=[c[0] for c in ROPE_CASES])
def test_broken_rope_file_refused(tmp_path, name, text, key, what):
    f = tmp_path / f"{name}.yaml"
    f.write_text(text)
    loaders = (load_params,) if name == "wrong_model" else (load_rope_params, load_params)
    for load in loaders:  # the file loader and the rope node's entry (models.load_params)
        with pytest.raises(RopeParamsError) as ei:
            load(f)
        msg = str(ei.value)
        assert msg.startswith(f"{name}.yaml: "), msg
        if key is not None:
            assert f"key '{key}'" in msg, msg
        assert what in msg, msg


CABLE_CASES = [
    ("c_empty", "", None, "the file is empty"),
    ("c_missing_model", _with(CABLE_TEXT, "model: DROP"), "model", None),
    ("c_missing_diameter", _with(CABLE_TEXT, "diameter: DROP"), "diameter", "required key is missing"),
    ("c_unknown_key", _with(CABLE_TEXT, "lenght: 170.0"), "lenght", "unknown key"),
    ("c_duplicate_key", CABLE_TEXT + "n_nodes: 9\n", "n_nodes", "duplicate key"),
    ("c_invalid_yaml", "model: fd_cable\nlength: {170\n", None, "not valid YAML"),
    ("c_nan", _with(CABLE_TEXT, "weight_in_water: .nan"), "weight_in_water", "got nan"),
    ("c_zero_length", _with(CABLE_TEXT, "length: 0.0"), "length", "[1, 10000] m"),
    ("c_ea_1e15", _with(CABLE_TEXT, "axial_stiffness: 1.0e+15"), "axial_stiffness", "[1000, 1e+10] N"),
    ("c_youngs_1e15", _with(CABLE_TEXT, "youngs_modulus: 1.0e+15"), "youngs_modulus", "Pa"),
    ("c_water_density", _with(CABLE_TEXT, "water_density: 1.0e-9"), "water_density", "[900, 1100]"),
    ("c_mass_1e30", _with(CABLE_TEXT, "mass_per_length: 1.0e+30"), "mass_per_length", "kg/m"),
    ("c_string", _with(CABLE_TEXT, "drag_normal: high"), "drag_normal", "got 'high'"),
    ("c_bool", _with(CABLE_TEXT, "added_mass_full_acceleration: maybe"), "added_mass_full_acceleration",
     "true or false"),
    ("c_n_nodes", _with(CABLE_TEXT, "n_nodes: 2"), "n_nodes", "an integer in [3, 2000]"),
    ("c_time_weight", _with(CABLE_TEXT, "time_weight: 0.2"), "time_weight", "[0.5, 1]"),
]


@pytest.mark.parametrize("name,text,key,what", CABLE_CASES, ids=[c[0] for c in CABLE_CASES])
def test_broken_cable_file_refused(tmp_path, name, text, key, what):
    f = tmp_path / f"{name}.yaml"
    f.write_text(text)
    with pytest.raises(FdCableParamsError) as ei:
        load_cable_params(f)
    assert isinstance(ei.value, RopeParamsError)  # one base class for both file kinds
    msg = str(ei.value)
    assert msg.startswith(f"{name}.yaml: "), msg
    if key is not None:
        assert f"key '{key}'" in msg, msg
    if what is not None:
        assert what in msg, msg


def test_invalid_yaml_names_line_not_a_traceback(tmp_path):
    f = tmp_path / "bad.yaml"
    f.write_text("length: 100.0\ndiameter: 0.05\nname: [table1\n")
    for call in (load_rope_params, rope_file_model):
        with pytest.raises(RopeParamsError, match=r"^bad\.yaml: line \d+: not valid YAML"):
            call(f)
    f.write_text("length: 100.0\nlength: 90.0\n")
    with pytest.raises(RopeParamsError, match=r"^bad\.yaml: line 2: key 'length': duplicate key"):
        rope_file_model(f)


def test_shipped_files_load_with_their_values():
    p = load_rope_params(default_rope_path())
    assert (p.length, p.diameter, p.mass_per_length, p.n_elements) == (100.0, 0.05, 1.725, 11)
    assert p.breaking_load == pytest.approx(16.0 * 9806.65, rel=1e-6)  # Table 1: 16 tf
    assert (p.winch_max_payout_speed, p.winch_max_heave_speed) == (3.0, 3.0)  # documented defaults
    c = load_cable_params(default_cable_path())
    assert (c.length, c.n_nodes, c.diameter, c.youngs_modulus) == (170.0, 7, 0.035, 4.4e8)
    assert c.ea == pytest.approx(4.4e8 * math.pi * 0.035 ** 2 / 4)
    assert rope_file_model(default_rope_path()) == "element_chain"
    assert rope_file_model(default_cable_path()) == "fd_cable"


def test_exponent_without_dot_is_a_number(tmp_path):
    """YAML 1.1 reads 4.4e8 as a string; the reader takes it as the number YAML 1.2 means."""
    f = tmp_path / "c.yaml"
    f.write_text(_with(CABLE_TEXT, "youngs_modulus: 4.4e8"))
    assert load_cable_params(f).youngs_modulus == 4.4e8
