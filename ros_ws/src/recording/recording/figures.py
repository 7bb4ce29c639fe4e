"""The figures of a recording (PNG, matplotlib with the Agg backend): the only module of
`analyze` that needs matplotlib. Which files it writes and what they show: analysis.py's
docstring and docs/tools.md. These are figures for people: speeds in knots, headings as compass
degrees true, rates of turn in deg/min (+ to port, as every signed angle here: REP-103); the
summary files keep SI.
"""
from __future__ import annotations

import math
import os
from typing import Dict, List, Optional

import numpy as np

from recording.measures import KN, towline_angle
from recording.recorded_run import Recording, status_column
from sim_math.trials import compass_deg

# status fields that are all zero on a vessel that was given no order and did nothing with one
ORDER_FIELDS = ("engine_order", "steering_angle_ordered", "steering_angle", "shaft_speed", "thrust")


def _rope_element_series(rope: dict, k: int, key: str):
    """Values of elements at fixed fractions along the rope (index by the current element count)."""
    fracs = np.linspace(0.0, 1.0, k)
    out = np.full((len(rope["t"]), k), np.nan)
    for j, arr in enumerate(rope["pos"] if key == "z" else rope["pitch"]):
        n = len(arr)
        if not n:
            continue
        idx = np.round(fracs * (n - 1)).astype(int)
        out[j] = arr[idx, 2] if key == "z" else arr[idx]
    return fracs, out


class _Figures:
    """Saves figures as PNG files in out_dir and keeps their paths."""

    def __init__(self, plt, out_dir: str, dpi: int):
        self.plt, self.out_dir, self.dpi = plt, out_dir, dpi
        self.files: List[str] = []

    def save(self, fig, name: str) -> None:
        path = os.path.join(self.out_dir, name)
        fig.tight_layout()
        fig.savefig(path, dpi=self.dpi)
        self.plt.close(fig)
        self.files.append(path)


def make_figures(rec: Recording, out_dir: str, elements: int = 5, snapshots: int = 6, dpi: int = 110,
                 turns: Optional[Dict[str, dict]] = None,
                 breaking: Optional[Dict[str, Optional[float]]] = None, sea: Optional[dict] = None) -> List[str]:
    """Every figure the recording has data for (see the module docstring); with `sea`
    (measures.analyse_sea) the sea statistics' figures too; their paths."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out = _Figures(plt, out_dir, dpi)
    if rec.vessels or rec.ropes:
        _tracks_figure(out, rec, snapshots)
    if rec.vessels:
        _yaw_figure(out, rec)
        _speed_yaw_rate_figure(out, rec)
        _motions_figure(out, rec)
    for name, v in rec.vessels.items():
        if "status" in v and len(v["status"]["t"]) and not never_ordered(v["status"]):
            _orders_figure(out, name, v)
    ropes = {n: r for n, r in rec.ropes.items() if "t" in r or "wrench_a" in r or "wrench_b" in r}
    if ropes:
        _tension_figure(out, rec, ropes, breaking or {})
    chains = {n: r for n, r in rec.ropes.items() if "pos" in r and len(r["t"])}
    if chains:
        _rope_element_figures(out, chains, elements)
    for name, m in (turns or {}).items():
        if "_along" in m:
            _turn_figure(out, name, m)
    if sea is not None:
        _sea_peaks_figure(out, sea)
        _motion_spectra_figure(out, sea)
    return out.files


def _tracks_figure(out: _Figures, rec: Recording, snapshots: int) -> None:
    """XY tracks of the vessels (heading arrows) and rope snapshots with paths of three elements."""
    plt = out.plt
    fig, ax = plt.subplots(figsize=(8, 7))
    for name, v in rec.vessels.items():
        line, = ax.plot(v["x"], v["y"], lw=1.6, label=f"{name}")
        ax.plot(v["x"][0], v["y"][0], "o", color=line.get_color(), ms=4)
        for j in np.linspace(0, len(v["t"]) - 1, snapshots).astype(int):  # heading arrows
            ax.annotate("", xy=(v["x"][j] + 8 * math.cos(v["yaw"][j]), v["y"][j] + 8 * math.sin(v["yaw"][j])),
                        xytext=(v["x"][j], v["y"][j]), arrowprops=dict(arrowstyle="->", color=line.get_color()))
    for name, rope in rec.ropes.items():
        if "pos" not in rope or not len(rope["t"]):
            continue
        cmap = plt.get_cmap("viridis")
        js = np.linspace(0, len(rope["t"]) - 1, snapshots).astype(int)
        for c, j in enumerate(js):
            p = rope["pos"][j]
            if len(p):
                ax.plot(p[:, 0], p[:, 1], ".-", ms=2, lw=0.8, color=cmap(c / max(1, len(js) - 1)),
                        label=f"{name} elements t={rope['t'][j]:.0f} s")
        fr, _ = _rope_element_series(rope, 3, "z")
        for f in fr:
            xs = [p[int(round(f * (len(p) - 1))), 0] if len(p) else np.nan for p in rope["pos"]]
            ys = [p[int(round(f * (len(p) - 1))), 1] if len(p) else np.nan for p in rope["pos"]]
            ax.plot(xs, ys, ":", lw=0.8, color="gray")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x east (m)")
    ax.set_ylabel("y north (m)")
    ax.set_title(f"XY tracks (map frame): {os.path.basename(rec.path)}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    out.save(fig, "tracks.png")


def never_ordered(status: dict) -> bool:
    """Whether a vessel's status shows no order and no response throughout (engine order, helm
    ordered and actual, shaft speed, thrust all zero): an unpowered barge, or a vessel left
    stopped. It gets no orders figure (an all-zero figure says nothing)."""
    return all(not np.any(status_column(status, f)) for f in ORDER_FIELDS)


def heading_deg_true(yaw: np.ndarray) -> np.ndarray:
    """Compass headings (deg true, [0, 360)) of REP-103 yaws, NaN where they cross north (no
    vertical line across the 0 / 360 seam)."""
    deg = np.array([compass_deg(float(y)) for y in yaw])
    deg[1:][np.abs(np.diff(deg)) > 180.0] = np.nan
    return deg


def _yaw_figure(out: _Figures, rec: Recording) -> None:
    """Heading of every vessel as a compass reads it (yaw.png: the file keeps its name)."""
    fig, ax = out.plt.subplots(figsize=(8, 4))
    spans = []
    for name, v in rec.vessels.items():
        deg = heading_deg_true(v["yaw"])
        ax.plot(v["t"], deg, label=name)
        spans += [np.nanmin(deg), np.nanmax(deg)] if np.any(np.isfinite(deg)) else []
    ax.set_xlabel("time (s)")
    ax.set_ylabel("heading (deg true)")
    if spans and max(spans) - min(spans) > 90.0:  # the whole compass; a small change keeps its scale
        ax.set_ylim(-5, 365)
        ax.set_yticks([0, 90, 180, 270, 360])
    ax.set_title("Headings")
    ax.grid(alpha=0.3)
    ax.legend()
    out.save(fig, "yaw.png")


def _speed_yaw_rate_figure(out: _Figures, rec: Recording) -> None:
    fig, axs = out.plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for name, v in rec.vessels.items():
        axs[0].plot(v["t"], v["speed"] / KN, label=name)
        axs[1].plot(v["t"], np.degrees(v["r"]) * 60.0, label=name)
    axs[0].set_ylabel("speed over ground (kn)")
    axs[1].set_ylabel("rate of turn (deg/min, + to port)")
    axs[1].set_xlabel("time (s)")
    for a in axs:
        a.grid(alpha=0.3)
        a.legend()
    axs[0].set_title("Speed and rate of turn")
    out.save(fig, "speed_yaw_rate.png")


NOISE_DEG = 0.01  # a roll or pitch history that never spans this much is a 3-DOF model's round-off


def _motions_figure(out: _Figures, rec: Recording) -> None:
    """Speed, and roll, pitch and rise where some vessel has them (a 3-DOF model's pitch is
    round-off and gets no panel; the rise is reported by planing hulls)."""
    panels = [("speed", "speed over ground (kn)", {n: (v["t"], v["speed"] / KN) for n, v in rec.vessels.items()})]
    for key, label in (("roll", "roll (deg, + stbd down)"), ("pitch", "pitch (deg, + bow down)")):
        series = {n: (v["t"], np.degrees(v[key])) for n, v in rec.vessels.items()}
        if any(np.ptp(y) > NOISE_DEG for _, y in series.values() if y.size):
            panels.append((key, label, series))
    risers = {n: (v["status"]["t"], status_column(v["status"], "rise")) for n, v in rec.vessels.items()
              if "status" in v and np.any(status_column(v["status"], "rise") != 0.0)}
    if risers:
        panels.append(("rise", "rise (m)", risers))
    fig, axs = out.plt.subplots(len(panels), 1, figsize=(8, max(3.5, 2.7 * len(panels))), sharex=True, squeeze=False)
    axs = axs[:, 0]
    for a, (_key, label, series) in zip(axs, panels):
        for name, (t, y) in series.items():
            a.plot(t, y, label=name)
        a.set_ylabel(label)
    axs[-1].set_xlabel("time (s)")
    for a in axs:
        a.grid(alpha=0.3)
        a.legend()
    axs[0].set_title("Speed" + "".join(f", {k}" for k, _, _ in panels[1:]) + " histories")
    out.save(fig, "motions.png")


def _orders_figure(out: _Figures, name: str, v: dict) -> None:
    """The orders a vessel was given and what they did: helm (or bucket) ordered and actual,
    engine order and shaft speed, thrust, and the girting ratio with its warning threshold when
    the vessel reports one."""
    st = v["status"]
    t = st["t"]
    girting = status_column(st, "girting_ratio")
    rows = 4 if np.any(girting != 0.0) else 3
    fig, axs = out.plt.subplots(rows, 1, figsize=(8, 2.5 * rows), sharex=True)
    axs[0].plot(t, np.degrees(status_column(st, "steering_angle_ordered")), "--", label="ordered")
    axs[0].plot(t, np.degrees(status_column(st, "steering_angle")), label="actual")
    axs[0].set_ylabel("rudder / nozzle (deg, + port)")
    axs[1].plot(t, status_column(st, "engine_order"), label="engine order")
    axs[1].set_ylabel("engine order (-1..1)")
    rpm = axs[1].twinx()
    rpm.plot(t, status_column(st, "shaft_speed") * 60.0 / (2.0 * math.pi), color="C3", lw=1, label="shaft")
    rpm.set_ylabel("shaft (rpm)", color="C3")
    axs[2].plot(t, status_column(st, "thrust") / 1e3, label="thrust")
    axs[2].set_ylabel("thrust (kN)")
    if rows == 4:
        axs[3].plot(t, girting, label="girting ratio")
        axs[3].plot(t, status_column(st, "girting_threshold"), "r--", lw=1, label="warning threshold")
        axs[3].set_ylabel("girting ratio")
    axs[-1].set_xlabel("time (s)")
    for a in axs:
        a.grid(alpha=0.3)
        a.legend(fontsize=7, loc="upper left")
    axs[0].set_title(f"Orders and response of {name}")
    out.save(fig, f"orders_{name}.png")


def _tension_figure(out: _Figures, rec: Recording, ropes: Dict[str, dict], breaking: Dict[str, Optional[float]]) -> None:
    """End tensions from the rope state, else from the end wrenches, with the breaking load;
    under each rope the towline angle at the ends that are made fast on a vessel."""
    angles: Dict[str, list] = {}
    for n in ropes:
        ends = ((towline_angle(rec, n, e), e) for e in ("a", "b"))
        angles[n] = [got + (e,) for got, e in ends if got]
    rows = sum(1 + bool(angles[n]) for n in ropes)
    fig, axs = out.plt.subplots(rows, 1, figsize=(8, 3.2 * rows), squeeze=False)
    axs = list(axs[:, 0])
    for name, rope in ropes.items():
        a = axs.pop(0)
        if "t" in rope:
            a.plot(rope["t"], rope["tension_a"] / 1e3, label=f"{name} end a")
            a.plot(rope["t"], rope["tension_b"] / 1e3, "--", label=f"{name} end b")
        else:
            for end in ("a", "b"):
                if f"wrench_{end}" in rope:
                    w = rope[f"wrench_{end}"]
                    a.plot(w["t"], w["tension"] / 1e3, label=f"{name} end {end} (wrench)")
        if breaking.get(name):
            a.axhline(breaking[name] / 1e3, color="r", ls=":", label=f"breaking load {breaking[name] / 1e3:.0f} kN")
        a.set_ylabel("tension (kN)")
        a.set_xlabel("time (s)")
        a.set_title(f"{name}: tension at both ends")
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
        if angles[name]:
            b = axs.pop(0)
            for vessel, t, ang, end in angles[name]:
                deg = np.degrees(ang)
                deg[1:][np.abs(np.diff(deg)) > 180.0] = np.nan  # no vertical line across the +-180 seam
                b.plot(t, deg, label=f"end {end} on {vessel}")
            b.set_ylabel("towline angle (deg from bow, + port)")
            b.set_xlabel("time (s)")
            b.set_ylim(-185, 185)
            b.set_yticks([-180, -90, 0, 90, 180])
            b.grid(alpha=0.3)
            b.legend(fontsize=7)
    out.save(fig, "towline_tension.png")


def _rope_element_figures(out: _Figures, chains: Dict[str, dict], elements: int) -> None:
    """Heights and pitch angles of `elements` elements spread along each rope."""
    for key, fname, ylabel, ttl in (("z", "rope_heights.png", "element height z (m)", "Rope element heights"),
                                    ("pitch", "rope_pitch.png", "element pitch (deg, + axis down to end a)",
                                     "Rope element pitch angles")):
        fig, axs = out.plt.subplots(len(chains), 1, figsize=(8, 3.8 * len(chains)), squeeze=False)
        for a, (name, rope) in zip(axs[:, 0], chains.items()):
            fracs, vals = _rope_element_series(rope, elements, key)
            for i, f in enumerate(fracs):
                y = vals[:, i] if key == "z" else np.degrees(vals[:, i])
                a.plot(rope["t"], y, lw=1, label=f"{name} element at {f:.2f} of length (end a = 0)")
            if key == "z":
                a.plot(rope["t"], rope["min_z"], "k--", lw=1, label=f"{name} lowest element")
            a.set_ylabel(ylabel)
            a.grid(alpha=0.3)
            a.legend(fontsize=7)
        axs[-1, 0].set_xlabel("time (s)")
        axs[0, 0].set_title(ttl)
        out.save(fig, fname)


def _turn_figure(out: _Figures, name: str, m: dict) -> None:
    """A turn in approach-course axes with the 90 and 180 deg points and the steady circle."""
    fig, ax = out.plt.subplots(figsize=(7, 7))
    ax.plot(m["_across"], m["_along"], lw=1.5, label=f"{name} track from execute (t0 = {m['t0']:.1f} s)")
    if math.isfinite(m.get("advance", math.nan)):
        ax.plot([m["transfer"]], [m["advance"]], "o", label=f"90 deg: advance {m['advance']:.1f} m, "
                                                             f"transfer {m['transfer']:.1f} m")
    if math.isfinite(m.get("tactical_diameter", math.nan)):
        j = int(np.argmax(m["_dpsi"] >= math.pi))
        ax.plot([m["tactical_diameter"]], [m["_along"][j]], "s",
                label=f"180 deg: tactical diameter {m['tactical_diameter']:.1f} m")
    if math.isfinite(m.get("steady_diameter", math.nan)):
        psi0, x0, y0 = m["_psi0"], m["_x0"], m["_y0"]
        c, s, side = math.cos(psi0), math.sin(psi0), m["turn_direction"]
        dx, dy = m["steady_centre_x"] - x0, m["steady_centre_y"] - y0
        ca, cx = c * dx + s * dy, side * (-s * dx + c * dy)
        ang = np.linspace(0, 2 * math.pi, 200)
        rr = m["steady_diameter"] / 2
        ax.plot(cx + rr * np.cos(ang), ca + rr * np.sin(ang), "k:", lw=1,
                label=f"steady circle: D = {m['steady_diameter']:.1f} m")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("transfer direction: across the approach course, towards the turn (m)")
    ax.set_ylabel("advance direction: along the approach course (m)")
    ax.set_title(f"Turning manoeuvre of {name}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    out.save(fig, f"turn_{name}.png")


def _sea_peaks_figure(out: _Figures, sea: dict) -> None:
    """Per rope, the exceedance probability of the tension peaks' amplitudes above the mean at
    each end (empirical, plotting position i / (n + 1)) on a log scale, with the fitted Weibull
    and the Rayleigh of the record's standard deviation."""
    from recording import sea_statistics as ss
    ends = [(name, e, st) for name, r in sea["ropes"].items() for e, st in r.items() if len(st.get("_amplitudes", ()))]
    if not ends:
        return
    fig, axs = out.plt.subplots(len(ends), 1, figsize=(8, 3.6 * len(ends)), squeeze=False)
    for a, (name, e, st) in zip(axs[:, 0], ends):
        amp = st["_amplitudes"] / 1e3
        a.semilogy(amp, ss.empirical_exceedance(amp), ".", ms=3, label=f"{name} {e.replace('_', ' ')}: "
                   f"{amp.size} peaks (maxima between mean up-crossings)")
        x = np.linspace(0.0, max(amp.max(), 1e-9) * 1.15, 200)
        if st.get("weibull_shape"):
            a.semilogy(x, ss.weibull_exceedance(x, st["weibull_shape"], st["weibull_scale"] / 1e3), "-",
                       label=f"Weibull fit: shape {st['weibull_shape']:.2f}, scale {st['weibull_scale'] / 1e3:.1f} kN "
                             f"(KS D {st['weibull_ks']:.3f})")
        if st.get("_sigma"):
            a.semilogy(x, ss.rayleigh_exceedance(x, st["_sigma"] / 1e3), "--",
                       label=f"Rayleigh, sigma {st['_sigma'] / 1e3:.1f} kN" +
                             (f" (KS D {st['rayleigh_ks']:.3f})" if st.get("rayleigh_ks") is not None else ""))
        a.set_ylim(max(0.5 / (amp.size + 1), 1e-4), 1.0)
        a.set_xlabel("peak tension above the mean (kN)")
        a.set_ylabel("probability of exceedance")
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7)
    lo, hi = sea.get("window_start"), sea.get("window_end")
    axs[0, 0].set_title("Towline tension peaks" + (f" from {lo:.0f} s" if lo is not None else "")
                        + (f" to {hi:.0f} s" if hi is not None else ""))
    out.save(fig, "sea_peaks.png")


def _motion_spectra_figure(out: _Figures, sea: dict) -> None:
    """Welch spectra of every vessel's heave, roll, pitch and yaw (one panel each; deg for the
    angles), with the significant value 4 sqrt(m0) and the peak period in the legend."""
    panels = (("heave", "heave (m^2 s)", 1.0), ("roll", "roll (deg^2 s)", math.degrees(1.0)),
              ("pitch", "pitch (deg^2 s)", math.degrees(1.0)), ("yaw", "yaw (deg^2 s)", math.degrees(1.0)))
    if not sea["vessels"]:
        return
    fig, axs = out.plt.subplots(len(panels), 1, figsize=(8, 2.6 * len(panels)), sharex=True)
    segment = None
    for a, (key, label, scale) in zip(axs, panels):
        for name, motions in sea["vessels"].items():
            sp = motions.get(key, {})
            if "_f" not in sp:
                continue
            segment = sp["segment"]
            unit = "m" if key == "heave" else "deg"
            tp = f", Tp {sp['peak_period']:.1f} s" if sp.get("peak_period") is not None else ""
            a.plot(sp["_f"], sp["_S"] * scale ** 2, label=f"{name}: 4 sqrt(m0) = {4 * math.sqrt(sp['m0']) * scale:.3g} "
                                                            f"{unit}{tp}")
        a.set_ylabel(label)
        a.grid(alpha=0.3)
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize=7)
    axs[-1].set_xlabel("frequency (Hz)")
    axs[-1].set_xlim(0.0, 0.5)
    axs[0].set_title("Motion spectra (Welch, Hann" + (f", {segment:.0f} s segments" if segment else "") + ", 50 % overlap)")
    out.save(fig, "sea_motion_spectra.png")
