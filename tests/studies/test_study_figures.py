"""A study's figures show SI values in the units a towing study is read in (kN, knots, m), and
say so on the axes."""
import matplotlib
import pandas as pd
import pytest

from studies.figures import display_unit, measure_figures

matplotlib.use("Agg")
KNOT = 1852.0 / 3600.0   # m/s, by definition


@pytest.mark.parametrize("key, unit, factor", [
    ("ropes.towline.tension_a_max", "kN", 1e-3),
    ("ropes.towline.sea_end_a.tension_significant", "kN", 1e-3),
    ("ropes.towline.peak_over_breaking_load", "", 1.0),
    ("ropes.towline.sea_end_a.slack_events", "", 1.0),
    ("vessels.tug.speed_end", "kn", 1.0 / KNOT),
    ("vessels.s175.turn.tactical_diameter", "m", 1.0),
    ("vessels.ship.ukc_min", "m", 1.0),
    ("ropes[towline].deployed_length", "m", 1.0),
    ("events[0].engine_order", "", 1.0),
    ("environment.waves.hs", "m", 1.0),
    ("environment.waves.tp", "s", 1.0),
])
def test_display_units(key, unit, factor):
    got_unit, got_factor = display_unit(key)
    assert got_unit == unit
    assert got_factor == pytest.approx(factor, rel=1e-12)


def test_figure_axes_carry_the_units_and_the_scaled_values(tmp_path, monkeypatch):
    import matplotlib.figure
    table = pd.DataFrame({"status": ["ok"] * 4, "ropes[towline].deployed_length": [90.0, 100.0, 90.0, 100.0],
                          "events[0].engine_order": [0.1, 0.1, 0.3, 0.3],
                          "peak": [20e3, 30e3, 50e3, 80e3]})
    saved = []
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", lambda fig, path, **kw: saved.append(fig))
    measure_figures(table, None, ["ropes[towline].deployed_length", "events[0].engine_order"],
                    {"peak": "ropes.towline.tension_a_max"}, str(tmp_path))
    ax = saved[0].axes[0]
    assert ax.get_ylabel() == "peak (kN)" and ax.get_xlabel() == "ropes[towline].deployed_length (m)"
    lines = {line.get_label(): line.get_ydata().tolist() for line in ax.get_lines()}
    assert lines["engine order 0.1"] == pytest.approx([20.0, 30.0]) and lines["engine order 0.3"] == pytest.approx([50.0, 80.0])
