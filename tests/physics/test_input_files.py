"""The one strict YAML reader of every input file (sim_math.input_files), checked against
what the YAML 1.2 spec and PyYAML's own SafeLoader say."""
import pytest
import yaml

from sim_math.input_files import YamlInputError, load_yaml, loads_yaml


def test_a_key_given_twice_is_an_error_with_both_lines():
    with pytest.raises(YamlInputError) as err:
        loads_yaml("a: 1\nb: 2\na: 3\n")
    e = err.value
    assert (e.duplicate_key, e.first_line, e.line) == ("a", 1, 3)
    assert "line 3" in str(e) and "duplicate key 'a'" in str(e)


def test_merge_keys_may_be_overridden():
    # YAML merge: the mapping's own key wins over a merged one; that is not a duplicate
    text = "base: &b {x: 1, y: 2}\nderived:\n  <<: *b\n  y: 5\n"
    assert loads_yaml(text)["derived"] == {"x": 1, "y": 5} == yaml.safe_load(text)["derived"]


@pytest.mark.parametrize("text,value", [("1e9", 1e9), ("4.4e8", 4.4e8), ("-2E-3", -2e-3), ("4.4e+8", 4.4e8),
                                        ("12", 12), ("0.5", 0.5)])
def test_exponent_numbers_read_as_yaml_1_2(text, value):
    got = loads_yaml(f"v: {text}\n")["v"]
    assert got == value and type(got) is type(value)


def test_strings_that_only_look_like_numbers_stay_strings():
    assert loads_yaml("v: e9\nw: '1e9'\nx: 1e\n") == {"v": "e9", "w": "1e9", "x": "1e"}


def test_file_errors_name_what_is_wrong(tmp_path):
    with pytest.raises(YamlInputError, match="cannot read"):
        load_yaml(str(tmp_path / "missing.yaml"))
    bad = tmp_path / "bad.yaml"
    bad.write_bytes(b"a: [1, 2\n")
    with pytest.raises(YamlInputError, match=r"line \d+, column \d+"):
        load_yaml(str(bad))
    bad.write_bytes(b"a: \xff\n")
    with pytest.raises(YamlInputError, match="not UTF-8"):
        load_yaml(str(bad))


def test_an_alias_bomb_is_refused_before_it_is_expanded(tmp_path):
    """Nine levels of nine aliases (a 600-byte file standing for 9^9 values) are refused with a
    short message: the scenario error once quoted the expanded value, 3.5 MB long."""
    text = 'a: &a ["x","x","x","x","x","x","x","x","x"]\n' + "".join(
        f"{c}: &{c} [*{p},*{p},*{p},*{p},*{p},*{p},*{p},*{p},*{p}]\n" for p, c in zip("abcdefgh", "bcdefghi"))
    assert len(text) < 700
    (tmp_path / "bomb.yaml").write_text(text)
    for load in (lambda: loads_yaml(text), lambda: load_yaml(str(tmp_path / "bomb.yaml"))):
        with pytest.raises(YamlInputError, match="aliases expand it to") as err:
            load()
        assert len(str(err.value)) < 200
    assert loads_yaml("a: &x [1, 2]\nb: *x\n") == {"a": [1, 2], "b": [1, 2]}  # aliases as such are fine


def test_nesting_deeper_than_the_reader_goes_is_an_input_error(tmp_path):
    """3000 nested lists (a RecursionError traceback before) are an input error like any other."""
    (tmp_path / "deep.yaml").write_text("description: " + "[" * 3000 + "]" * 3000 + "\n")
    with pytest.raises(YamlInputError, match="nested deeper"):
        load_yaml(str(tmp_path / "deep.yaml"))


def test_a_file_read_again_is_its_own_copy_and_an_edit_is_seen(tmp_path):
    """load_yaml keeps parsed documents by their bytes (a run's start reads one ship file dozens of
    times): a caller changing what it got changes nothing for the next, and an edited file (same
    path) is parsed anew, its errors as well."""
    path = tmp_path / "ship.yaml"
    path.write_text("hull: {mass: 1000.0, inertia: [1, 2, 3]}\n")
    first = load_yaml(str(path))
    first["hull"]["inertia"].append(99)
    first["hull"]["mass"] = -1
    assert load_yaml(str(path)) == {"hull": {"mass": 1000.0, "inertia": [1, 2, 3]}}
    path.write_text("hull: {mass: 2000.0, inertia: [1, 2, 3]}\n")
    assert load_yaml(str(path))["hull"]["mass"] == 2000.0
    path.write_text("hull: {mass: 1, mass: 2}\n")
    with pytest.raises(YamlInputError, match="duplicate key 'mass'"):
        load_yaml(str(path))
    with pytest.raises(YamlInputError, match="duplicate key 'mass'"):  # an error is not kept as a document
        load_yaml(str(path))
