"""The scenario check's physical limits (issue 30 items 5 and 6), in-process and without ROS.

Truths used:
- a straight layout's tolerance: Table 1's rope (100 m, 16 tf breaking load at 15 % elongation,
  linear) reaches 115 m at its breaking load; a straight layout is accepted for ends 98-115 m
  apart and refused outside, each edge to 0.1 m;
- the 2 % slack the tolerance lets through sags as a shallow parabola does, sqrt(3 D dL / 8)
  = 8.66 % of the span (within 2 %);
- a contact's stiffness: the largest value the refusal quotes for the damping given is itself
  accepted and 1 % more is refused (the quoted bound is the check's), and the largest for any
  damping is omega h = 1/2 for the effective mass the message states (within its 3 digits),
  accepted with the damping quoted for it.
"""
import glob
import math
import os
import re

import numpy as np
import pytest

from scenario_format.scenario import ScenarioError, load_scenario

SCENARIOS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src", "scenario_runner",
                         "scenarios")

STRAIGHT = """name: fit
duration: 1.0
ropes:
  - name: line
    rope_file: table1.yaml
    end_a: fixed
    end_a_position: [0.0, 0.0, 0.0]
    end_b: fixed
    end_b_position: [{span}, 0.0, 0.0]
    layout: straight
"""


def _load(tmp_path, text):
    path = tmp_path / "fit.yaml"
    path.write_text(text)
    return load_scenario(str(path))


@pytest.mark.parametrize("span, accepted", [(97.9, False), (98.1, True), (100.0, True), (114.9, True),
                                            (115.1, False)])
def test_a_straight_layout_must_fit_its_rope(tmp_path, span, accepted):
    text = STRAIGHT.format(span=span)
    if accepted:
        _load(tmp_path, text)
        return
    with pytest.raises(ScenarioError) as err:
        _load(tmp_path, text)
    message = str(err.value)
    assert "fit.yaml: key 'ropes[0].layout'" in message and f"{span:.1f} m apart" in message
    assert "98.0 m to 115.0 m apart" in message or "reaches at most 115.0 m" in message, message


def test_a_short_straight_span_names_what_fits_or_is_allowed_on_purpose(tmp_path):
    with pytest.raises(ScenarioError) as err:
        _load(tmp_path, STRAIGHT.format(span=40.0))
    message = str(err.value)
    for text in ("40.0 m apart", "is 100 m long", "60.0 m folded", "layout: winch with deployed_length: 41",
                 "layout: slack", "allow_slack: true"):
        assert text in message, message
    _load(tmp_path, STRAIGHT.format(span=40.0) + "    allow_slack: true\n")   # said so: laid as asked


def test_two_percent_of_slack_sags_as_the_tolerance_says():
    from rope_model.layout import catenary_curve
    span = 100.0
    curve = catenary_curve((0.0, 0.0, 0.0), (span, 0.0, 0.0), 1.02 * span)
    sag = -curve[:, 2].min()
    assert sag / span == pytest.approx(math.sqrt(3.0 * 0.02 / 8.0), rel=0.02)   # 8.66 % of the span


def test_the_contact_stiffness_quoted_as_largest_is_the_bound(tmp_path):
    base = open(os.path.join(SCENARIOS, "assist_s175_push_pull.yaml")).read()
    with_k = lambda k: base.replace("    hull: ship\n", f"    hull: ship\n    stiffness: {k!r}\n")  # noqa: E731
    with pytest.raises(ScenarioError) as err:
        _load(tmp_path, with_k(1.0e10))
    message = str(err.value)
    assert "key 'contacts[0].stiffness'" in message and "omega h = 4.74" in message, message
    k_here = float(re.search(r"the stiffness must be below ([0-9.e+]+) N/m", message).group(1))
    k_max, c_best = map(float, re.search(r"no damping allows more than ([0-9.e+]+) N/m \(at ([0-9.e+]+) N s/m\)",
                                         message).groups())
    m_eff = float(re.search(r"is ([0-9.e+]+) kg", message).group(1))
    assert math.sqrt(k_max / m_eff) / 50.0 == pytest.approx(0.5, rel=5e-3)
    _load(tmp_path, with_k(k_here))                     # with the default damping, 4e5 N s/m
    with pytest.raises(ScenarioError, match=r"contacts\[0\]\.damping"):   # omega h < 1/2 still: the damping
        _load(tmp_path, with_k(1.01 * k_here))
    _load(tmp_path, with_k(k_max).replace(f"stiffness: {k_max!r}\n", f"stiffness: {k_max!r}\n    damping: {c_best!r}\n"))


def _checked_by_this():
    out = []
    for path in sorted(glob.glob(os.path.join(SCENARIOS, "*.yaml"))):
        text = open(path).read()
        if "contacts:" in text or "layout: straight" in text:
            out.append(os.path.basename(path))
    return out


@pytest.mark.parametrize("name", _checked_by_this())
def test_library_scenarios_with_contacts_or_straight_ropes_pass(name):
    sc = load_scenario(os.path.join(SCENARIOS, name))
    assert sc.contacts or any(r.layout == "straight" for r in sc.ropes)
