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


def test_monte_carlo_histogram_carries_the_gumbel_fit_as_expected_runs_and_the_mpm(tmp_path, monkeypatch):
    """A study over seeds only: the histogram of the runs' maxima (kN) with the fitted Gumbel
    density drawn as expected runs per bin, whose area over the bin width is the number of runs
    (the Gumbel CDF's difference over the drawn range, from loc - 3 scale), and the MPM line at the statistics' value."""
    import matplotlib.figure
    import numpy as np
    loc, scale, n = 60e3, 2e3, 40
    table = pd.DataFrame({"status": ["ok"] * n, "peak": np.linspace(56e3, 68e3, n)})
    stats = pd.DataFrame([{"peak_gumbel_loc": loc, "peak_gumbel_scale": scale, "peak_gumbel_mpm": 71e3,
                           "peak_gumbel_mpm_low": 69e3, "peak_gumbel_mpm_high": 73e3}])

    class Extremes:
        measure, duration = "peak", 10800.0
    saved = []
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", lambda fig, path, **kw: saved.append(fig))
    measure_figures(table, stats, [], {"peak": "ropes.towline.sea_end_a.tension_max"}, str(tmp_path), Extremes())
    ax = saved[0].axes[0]
    width = ax.patches[0].get_width()
    curve = [line for line in ax.get_lines() if line.get_label().startswith("Gumbel")][0]
    x, y = curve.get_xdata(), curve.get_ydata()
    z0, z1 = (1e3 * x[0] - loc) / scale, (1e3 * x[-1] - loc) / scale   # kN on the axis
    assert z0 == pytest.approx(-3.0)
    cdf = lambda z: np.exp(-np.exp(-z))  # noqa: E731 - the standard Gumbel's CDF
    assert np.trapezoid(y, x) / width == pytest.approx(n * (cdf(z1) - cdf(z0)), rel=1e-3)
    mpm = [line for line in ax.get_lines() if line.get_label().startswith("MPM")][0]
    assert mpm.get_xdata()[0] == pytest.approx(71.0)
