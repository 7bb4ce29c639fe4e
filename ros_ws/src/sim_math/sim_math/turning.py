"""Turning-circle measures from a sampled track (pure numpy, no ROS), written once and used by
the trials of the physics packages, ``analyze`` and the README tables alike.

Definitions (ITTC 7.5-04-02-01 and IMO MSC.137(76) terms; every angle in the REP-103 sense,
heading = yaw of the body x axis, counter-clockwise from east):

- execute point t0: the simulation time the helm order of the turn was given (analysis takes it
  from the vessel's command or status topic). Origin O = position of the vessel's reference
  point at t0 (linear interpolation in time); approach course psi0 = heading at t0.
- heading change dpsi(t) = s * (psi(t) - psi0) with psi unwrapped (continuous through +-180
  deg) and s = +1 for a turn to port, -1 to starboard (the sign of the heading change at the
  end of the turn), so dpsi grows through 90, 180, 360 deg as the vessel turns.
- along(t) = (p(t) - O) . (cos psi0, sin psi0), across(t) = s * (p(t) - O) . (-sin psi0, cos psi0):
  distances along the approach course and perpendicular to it, towards the side of the turn.
- advance = along and transfer = across at the first time dpsi reaches 90 deg; tactical
  diameter = across at the first time dpsi reaches 180 deg (linear interpolation between the
  two samples either side of the crossing). Times to 90 and 180 deg are reported too.
- steady turn: the samples with dpsi >= max(steady_from, dpsi_end - 360 deg) (default
  steady_from = 180 deg): the last full revolution of the turn, but never its first half.
  The window must span at least 90 deg of heading change, else the steady values are NaN
  ("turn too short").
- steady turning diameter = 2 R of the least-squares circle through the window's positions
  (algebraic Kasa fit refined by Gauss-Newton on the geometric distances); the fit's RMS
  residual and its centre are reported. The kinematic value 2 U / |r| over the same window
  is reported as a cross-check (they agree when the turn is steady and there is no current).
- steady speed U = mean of sqrt(u^2 + v^2) (body velocities over ground), steady yaw rate
  r = mean of r, drift angle beta = mean of atan2(-v, u) (positive = bow inside the circle
  for a port turn) over the window; approach speed U0 = speed at t0; speed loss = U / U0.
"""
from __future__ import annotations

import math
from typing import Dict, Optional, Tuple

import numpy as np


def circle_fit(x: np.ndarray, y: np.ndarray, iterations: int = 20) -> Tuple[float, float, float, float]:
    """Least-squares circle (xc, yc, R, rms residual) through the points."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    if x.size < 3:
        return math.nan, math.nan, math.nan, math.nan
    mx, my = x.mean(), y.mean()
    u, v = x - mx, y - my  # centred for conditioning
    a = np.column_stack([u, v, np.ones_like(u)])
    sol, *_ = np.linalg.lstsq(a, u * u + v * v, rcond=None)
    uc, vc = 0.5 * sol[0], 0.5 * sol[1]
    r = math.sqrt(max(sol[2] + uc * uc + vc * vc, 0.0))
    for _ in range(iterations):  # Gauss-Newton on d_i = |p_i - c| - R
        du, dv = u - uc, v - vc
        rho = np.hypot(du, dv)
        rho[rho == 0] = 1e-12
        res = rho - r
        jac = np.column_stack([-du / rho, -dv / rho, -np.ones_like(rho)])
        step, *_ = np.linalg.lstsq(jac, -res, rcond=None)
        uc, vc, r = uc + step[0], vc + step[1], r + step[2]
        if np.max(np.abs(step)) < 1e-10 * max(1.0, abs(r)):
            break
    rms = float(np.sqrt(np.mean((np.hypot(u - uc, v - vc) - r) ** 2)))
    return float(uc + mx), float(vc + my), float(abs(r)), rms


def _interp_at(t: np.ndarray, values: np.ndarray, t0: float) -> float:
    return float(np.interp(t0, t, values))


def turning_measures(t, x, y, psi, u, v, r, t0: float, t1: Optional[float] = None,
                     steady_from_deg: float = 180.0) -> Dict[str, float]:
    """The measures of the module docstring for the turn from t0 to t1 (default: end of data).
    psi may be wrapped; it is unwrapped here. Returns a dict of SI values (m, s, rad, m/s, rad/s)
    plus 'notes' (str) saying what could not be measured and why."""
    t = np.asarray(t, float)
    x, y, u, v, r = (np.asarray(a, float) for a in (x, y, u, v, r))
    psi_u = np.unwrap(np.asarray(psi, float))
    t1 = float(t[-1]) if t1 is None else float(t1)
    notes = []
    out: Dict[str, float] = {"t0": float(t0), "t1": t1}
    sel = (t >= t0) & (t <= t1)
    if sel.sum() < 3:
        out["notes"] = "fewer than 3 samples in the turn"
        return out
    # origin and approach course at t0 (interpolated), then the samples of the turn after it
    x0, y0, psi0 = _interp_at(t, x, t0), _interp_at(t, y, t0), _interp_at(t, psi_u, t0)
    speed = np.hypot(u, v)
    out["approach_speed"] = _interp_at(t, speed, t0)
    out["approach_heading"] = float(math.atan2(math.sin(psi0), math.cos(psi0)))
    tt = np.concatenate([[t0], t[sel & (t > t0)]])
    xx = np.concatenate([[x0], x[sel & (t > t0)]])
    yy = np.concatenate([[y0], y[sel & (t > t0)]])
    pp = np.concatenate([[psi0], psi_u[sel & (t > t0)]])
    side = 1.0 if pp[-1] - psi0 >= 0 else -1.0
    out["turn_direction"] = side  # +1 port, -1 starboard
    dpsi = side * (pp - psi0)
    c, s = math.cos(psi0), math.sin(psi0)
    along = c * (xx - x0) + s * (yy - y0)
    across = side * (-s * (xx - x0) + c * (yy - y0))
    out["heading_change"] = float(dpsi[-1])

    def crossing(angle: float):
        above = np.nonzero(dpsi >= angle)[0]
        if above.size == 0:
            return None
        j = int(above[0])
        if j == 0:
            return float(tt[0]), float(along[0]), float(across[0])
        f = (angle - dpsi[j - 1]) / (dpsi[j] - dpsi[j - 1])
        lerp = lambda a: float(a[j - 1] + f * (a[j] - a[j - 1]))  # noqa: E731
        return lerp(tt), lerp(along), lerp(across)

    c90, c180 = crossing(math.pi / 2), crossing(math.pi)
    if c90:
        out["time_to_90"], out["advance"], out["transfer"] = c90[0] - t0, c90[1], c90[2]
    else:
        out["advance"] = out["transfer"] = out["time_to_90"] = math.nan
        notes.append(f"heading changed only {math.degrees(dpsi[-1]):.1f} deg: no advance/transfer (90 deg)")
    if c180:
        out["time_to_180"], out["tactical_diameter"] = c180[0] - t0, c180[2]
    else:
        out["tactical_diameter"] = out["time_to_180"] = math.nan
        notes.append(f"heading changed only {math.degrees(dpsi[-1]):.1f} deg: no tactical diameter (180 deg)")

    # steady part: last full revolution, never before steady_from
    lo = max(math.radians(steady_from_deg), dpsi[-1] - 2 * math.pi)
    w = dpsi >= lo
    out["steady_window_from"] = float(lo)
    out["steady_window_span"] = float(dpsi[-1] - lo) if w.any() else 0.0
    keys = ("steady_diameter", "steady_centre_x", "steady_centre_y", "steady_fit_rms", "steady_speed",
            "steady_yaw_rate", "steady_drift_angle", "steady_diameter_kinematic", "speed_loss", "steady_t_start")
    if not w.any() or dpsi[-1] - lo < math.pi / 2 - 1e-9:
        for k in keys:
            out[k] = math.nan
        notes.append(f"turn too short for a steady diameter: needs heading change >= "
                     f"{steady_from_deg + 90:.0f} deg, got {math.degrees(dpsi[-1]):.1f} deg")
    else:
        xc, yc, radius, rms = circle_fit(xx[w], yy[w])
        tw0 = float(tt[w][0])
        mask = (t >= tw0) & (t <= t1)
        out["steady_t_start"] = tw0
        out["steady_diameter"] = 2.0 * radius
        out["steady_centre_x"], out["steady_centre_y"], out["steady_fit_rms"] = xc, yc, rms
        out["steady_speed"] = float(np.mean(speed[mask]))
        out["steady_yaw_rate"] = float(np.mean(r[mask]))
        out["steady_drift_angle"] = float(np.mean(np.arctan2(-v[mask], u[mask])))
        out["steady_diameter_kinematic"] = (2.0 * out["steady_speed"] / abs(out["steady_yaw_rate"])
                                            if out["steady_yaw_rate"] else math.inf)
        out["speed_loss"] = out["steady_speed"] / out["approach_speed"] if out["approach_speed"] > 1e-9 else math.nan
    out["notes"] = "; ".join(notes)
    # for plotting
    out["_along"], out["_across"], out["_dpsi"], out["_t"] = along, across, dpsi, tt
    return out
