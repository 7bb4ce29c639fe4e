"""Bad-input and robustness tests of rope_model: clear messages, no silent NaN."""
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src", "rope_model"))

from rope_model import (TONNE_FORCE, RopeChain, RopeDivergedError, RopeParams,  # noqa: E402
                        RopeParamsError, default_rope_path, load_rope_params)

TABLE1 = load_rope_params(default_rope_path())


def test_table1_yaml_is_the_paper_rope():
    p = TABLE1
    assert p.length == 100.0 and p.diameter == 0.05 and p.n_elements == 11
    assert p.mass_per_length == 1.725  # 1.725 kgf/m -> kg/m
    assert p.breaking_load == pytest.approx(16.0 * 9806.65, rel=1e-6)  # 16 tf
    assert p.ea == pytest.approx(16.0 * 9806.65 / 0.15, rel=1e-6)
    assert (p.drag_normal, p.drag_tangential) == (1.2, 0.015)
    assert TONNE_FORCE == pytest.approx(9806.65)


def _write(tmp_path, name, text):
    f = tmp_path / name
    f.write_text(text)
    return f


def _table1_with(line):
    """The shipped table1.yaml with the key of `line` ("key: value") replaced by it (appended
    if the key is new): every other key valid, so the error can only be about this one."""
    key = line.split(":")[0]
    out, done = [], False
    for old in open(default_rope_path()).read().splitlines():
        if old.split(":")[0] == key:
            out.append(line)
            done = True
        else:
            out.append(old)
    if not done:
        out.append(line)
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("line,what", [
    ("diameter: -1", "expected a number in [0.001, 0.5] m, got -1"),
    ("length: 0", "expected a number in [1, 10000] m, got 0"),
    ("length: -5.0", "expected a number in [1, 10000] m, got -5.0"),
    ("mass_per_length: abc", "expected a number in [0.001, 1000] kg/m, got 'abc'"),
    ("n_elements: 0", "expected an integer in [1, 2000], got 0"),
    ("n_elements: 2.5", "expected an integer in [1, 2000], got 2.5"),
    ("drag_normal: -0.1", "expected a number in [0, 3], got -0.1"),
    ("diamter: 0.05", "unknown key (misspelt?"),
    ("breaking_load: .nan", "expected a number in [100, 1e+08] N, got nan"),
])
def test_bad_yaml_names_file_and_key(tmp_path, line, what):
    f = _write(tmp_path, "bad_rope.yaml", _table1_with(line))
    key = line.split(":")[0]
    with pytest.raises(RopeParamsError) as ei:
        load_rope_params(f)
    msg = str(ei.value)
    assert msg.startswith(f"bad_rope.yaml: key '{key}':"), msg
    assert what in msg, msg
    assert isinstance(ei.value, ValueError)


def test_bad_yaml_message_exact(tmp_path):
    f = _write(tmp_path, "table1.yaml", _table1_with("diameter: -1"))
    with pytest.raises(ValueError, match=r"^table1\.yaml: key 'diameter': expected a number in "
                                         r"\[0\.001, 0\.5\] m, got -1$"):
        load_rope_params(f)


def test_not_a_mapping_and_invalid_yaml(tmp_path):
    with pytest.raises(RopeParamsError, match="list.yaml"):
        load_rope_params(_write(tmp_path, "list.yaml", "- 1\n- 2\n"))
    with pytest.raises(RopeParamsError, match=r"broken.yaml: line 2: not valid YAML"):
        load_rope_params(_write(tmp_path, "broken.yaml", "length: [1, 2\n"))


def test_missing_file(tmp_path):
    missing = tmp_path / "nope.yaml"
    with pytest.raises(FileNotFoundError, match="rope parameter file not found: .*nope.yaml"):
        load_rope_params(missing)


def test_model_selector_key(tmp_path):
    p = load_rope_params(_write(tmp_path, "m.yaml", "model: element_chain\n" + _table1_with("length: 80")))
    assert p.length == 80.0
    with pytest.raises(RopeParamsError, match="c.yaml: key 'model'"):
        load_rope_params(_write(tmp_path, "c.yaml", _table1_with("model: fd_cable")))


def test_optional_keys_keep_defaults(tmp_path):
    """Only the rope itself is required; the model and environment keys default."""
    text = ("length: 50\ndiameter: 0.05\nmass_per_length: 1.725\nbreaking_load: 156906.4\n"
            "elongation_at_break: 0.15\ndrag_normal: 1.2\ndrag_tangential: 0.015\n")
    p = load_rope_params(_write(tmp_path, "short.yaml", text))
    assert p.length == 50.0 and p.n_elements == 11 and p.water_density == 1025.0
    assert p.winch_max_payout_speed == 3.0 and p.winch_max_heave_speed == 3.0


def test_zero_and_bad_element_counts():
    for n in (0, -3, 2.5, True):
        with pytest.raises(ValueError, match="n_elements"):
            RopeChain.straight(TABLE1, (0, 0, 0), (100, 0, 0), n_elements=n)


def test_nonpositive_lengths_rejected():
    with pytest.raises(ValueError, match="length"):
        TABLE1.replace(length=0.0)
    with pytest.raises(ValueError, match="length"):
        RopeChain.slack(TABLE1, (0, 0, 0), (50, 0, 0), length=-1.0)
    with pytest.raises(ValueError, match="deployed_length"):
        RopeChain.wound_on_winch(TABLE1, (0, 0, 2), (0, 0, 1), deployed_length=0.0)
    with pytest.raises(ValueError, match="lengths must be positive"):
        RopeChain(TABLE1, np.zeros((2, 3)), [[1, 0, 0], [1, 0, 0]], [1.0, -1.0])


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_nonfinite_attachment_state_rejected_without_change(bad):
    rope = RopeChain.slack(TABLE1, (0, 0, 10), (80, 0, 10), n_elements=11)
    rope.step(0.02)
    before = (rope.positions, rope.velocities, rope.attachment_position("a"))
    with pytest.raises(ValueError, match="end a position: must be finite"):
        rope.set_end_kinematics("a", (0.0, bad, 10.0), (0, 0, 0))
    with pytest.raises(ValueError, match="end b velocity: must be finite"):
        rope.set_end_kinematics("b", (80.0, 0, 10.0), (bad, 0, 0))
    with pytest.raises(ValueError, match="3 numbers"):
        rope.set_end_kinematics("a", (0.0, 10.0), (0, 0, 0))
    with pytest.raises(ValueError, match="'a' or 'b'"):
        rope.set_end_kinematics("c", (0.0, 0, 10.0), (0, 0, 0))
    assert np.array_equal(before[0], rope.positions)
    assert np.array_equal(before[1], rope.velocities)
    assert np.array_equal(before[2], rope.attachment_position("a"))
    rope.step(0.02)
    assert np.all(np.isfinite(rope.positions))


def test_other_bad_arguments():
    rope = RopeChain.slack(TABLE1, (0, 0, 10), (80, 0, 10), n_elements=5, end_b="free")
    for dt in (0.0, -0.02, math.nan, math.inf):
        with pytest.raises(ValueError, match="dt must be positive"):
            rope.step(dt)
    with pytest.raises(ValueError, match="only a pinned end can move"):
        rope.set_end_kinematics("b", (1, 2, 3), (0, 0, 0))
    with pytest.raises(ValueError, match="no winch"):
        rope.set_payout_rate(1.0)
    with pytest.raises(ValueError, match="end_a"):
        RopeChain.straight(TABLE1, (0, 0, 0), (100, 0, 0), end_a="glued")
    w = RopeChain.wound_on_winch(TABLE1, (0, 0, 2), (0, 0, 1))
    with pytest.raises(ValueError, match="payout rate must be finite"):
        w.set_payout_rate(math.nan)
    with pytest.raises(TypeError, match="RopeParams"):
        RopeChain.straight({"length": 100}, (0, 0, 0), (100, 0, 0))


def test_divergence_detected_and_reported():
    rope = RopeChain.slack(TABLE1, (0, 0, 10), (80, 0, 10), n_elements=11)
    rope.breaking_load[:] = np.inf  # per-connection strength; else the rope just parts
    for _ in range(5):
        rope.step(0.02)
    snap = (rope.positions.copy(), rope.velocities.copy(), rope.time, rope.tensions.copy())
    # an absurd attachment jump (a broken upstream signal): 1e6 m in one exchange step
    rope.set_end_kinematics("a", (0.0, 1.0e6, 10.0), (0, 0, 0))
    with pytest.raises(RopeDivergedError) as ei:
        rope.step(0.02)
    err = ei.value
    msg = str(err)
    assert "step 6" in msg and "element" in msg and "t = " in msg
    assert err.step == 6 and 0 <= err.element < 11
    # last good state kept, nothing NaN
    assert np.array_equal(rope.positions, snap[0])
    assert np.array_equal(rope.velocities, snap[1])
    assert rope.time == snap[2]
    assert np.array_equal(rope.tensions, snap[3])
    assert np.all(np.isfinite(rope.positions))


def test_params_object_validation():
    with pytest.raises(RopeParamsError, match="key 'diameter'"):
        RopeParams().replace(diameter=math.nan)
    with pytest.raises(RopeParamsError, match="key 'elongation_at_break'"):
        RopeParams().replace(elongation_at_break=15.0)
