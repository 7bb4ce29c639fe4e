"""Standard trials on any Vessel: straight run, turning circle, stopping; used by tests,
benchmarks and the README tables. Pure post-processing of trajectories, no physics here."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Dict, Optional, Sequence

import numpy as np

from sim_math.turning import turning_measures

from .vessel import Command, ExternalWrench, Vessel, VesselState

KN = 1852.0 / 3600.0


@dataclass
class Track:
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    psi: np.ndarray
    u: np.ndarray
    v: np.ndarray
    r: np.ndarray
    extra: Dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def speed(self) -> np.ndarray:
        return np.hypot(self.u, self.v)


def run(vessel: Vessel, duration: float, dt: float,
        events: Optional[Dict[float, Command]] = None,
        wrenches: Callable[[Vessel, float], Sequence[ExternalWrench]] = lambda v, t: (),
        record: Sequence[str] = ()) -> Track:
    """Step the vessel for duration s; events maps a time to a command applied at that time.

    record: names of status fields (StatusRecord attributes) to keep in Track.extra."""
    events = dict(events or {})
    times = sorted(events)
    n = int(round(duration / dt))
    out = np.zeros((n + 1, 7))
    rec = {k: np.zeros(n + 1) for k in record}

    def sample(i, t):
        s = vessel.state
        out[i] = (t, s.position[0], s.position[1], s.rpy[2], s.linear_velocity_body[0],
                  s.linear_velocity_body[1], s.angular_velocity_body[2])
        if record:
            st = vessel.status()
            for k in record:
                rec[k][i] = float(getattr(st, k))

    t = 0.0
    k = 0
    sample(0, t)
    for i in range(1, n + 1):
        while k < len(times) and times[k] <= t + 1e-9:
            vessel.set_command(events[times[k]])
            k += 1
        vessel.step(dt, wrenches(vessel, t))
        t = i * dt
        sample(i, t)
    return Track(*out.T, extra=rec)


def steady_straight(vessel: Vessel, engine_order: float, u0: float, duration: float, dt: float) -> float:
    """Final surge speed after running straight at a fixed engine order from speed u0."""
    vessel.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([u0, 0, 0.0]), np.zeros(3)))
    tr = run(vessel, duration, dt, {0.0: Command(engine_order, 0.0)})
    return float(tr.u[-1])


def turning_metrics(tr: Track, t0: float = 0.0, t1: Optional[float] = None) -> Dict[str, float]:
    """The turning-circle measures of sim_math.turning.turning_measures (advance, transfer,
    tactical diameter, steady diameter = circle fitted to the last full revolution, steady
    speed, yaw rate, drift angle, ...; definitions and keys there) of the turn whose helm
    order was given at t0. Only adapts a Track to the arrays; no measure is defined here."""
    return turning_measures(tr.t, tr.x, tr.y, tr.psi, tr.u, tr.v, tr.r, t0, t1)


def distance_run(tr: Track) -> np.ndarray:
    """Cumulative distance over ground along the track."""
    ds = np.hypot(np.diff(tr.x), np.diff(tr.y))
    return np.concatenate([[0.0], np.cumsum(ds)])


def readme_tables() -> str:
    """The README's result tables (python -m tug_dynamics.maneuver_trials): the block between
    <!-- tables:start --> and <!-- tables:end --> in ros_ws/src/tug_dynamics/README.md, as is.
    Turning measures from turning_metrics (sim_math.turning definitions)."""
    from .ship_file import load_ship
    from .vessel import ANCHOR_LET_GO
    lines = []
    # ---- Yun & Kim barge, simple towline ----
    lines += ["### Seed 002 barge, simple towline (Eq 3, Table 6: 0.857 m/s, 59.779 N, 2 deg/s)", "",
              "| gamma_max | steady speed m/s | steady yaw rate deg/s | drift angle deg | steady diameter m | D / L | tactical diameter / L |",
              "|---|---|---|---|---|---|---|"]
    for g in (10, 20, 30):
        b = load_ship("barge_002_model.yaml", overrides={"towline_simple": {"enabled": True, "gamma_max_deg": g}})
        b.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([0.857, 0, 0.0]), np.zeros(3)))
        tr = run(b, 400.0, 0.05)
        m = turning_metrics(tr)
        beta = math.degrees(m["steady_drift_angle"])
        lines.append(f"| {g} deg | {m['steady_speed']:.3f} | {math.degrees(m['steady_yaw_rate']):.2f} | {beta:.1f} | "
                     f"{m['steady_diameter']:.1f} | {m['steady_diameter'] / 5.0:.2f} | {m['tactical_diameter'] / 5.0:.2f} |")
    # ---- S-175 ----
    rated = 89.0
    half, slow = 44.5 / rated, 29.69 / rated

    def ship(u_kn, eo):
        s = load_ship("s175_003.yaml")
        s.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([u_kn * KN, 0, 0.0]), np.zeros(3)),
                    shaft_rps=eo * rated / 60.0)
        return s

    lines += ["", "### S-175 (seed 003), straight runs and stopping (800 s unless noted)", "",
              "| scenario | final speed kn | distance in 800 s m | head reach to 1 kn m |", "|---|---|---|---|"]
    for label, eo, kn in (("half ahead 44.5 rpm, no anchor", half, 9.0), ("slow ahead 29.69 rpm, no anchor", slow, 6.0)):
        s = ship(kn, eo)
        tr = run(s, 1500.0, 1.0, {0.0: Command(eo, 0.0)})
        lines.append(f"| {label} (steady, 1500 s) | {tr.u[-1] / KN:.2f} | - | - |")
    for anc in (False, True):
        s = ship(5.84, slow)
        tr = run(s, 800.0, 1.0, {0.0: Command(slow, 0.0, ANCHOR_LET_GO if anc else 0)})
        lines.append(f"| 1: slow ahead {'with anchor let go at 0 s' if anc else 'normal'} | {tr.u[-1] / KN:.2f} | "
                     f"{distance_run(tr)[-1]:.0f} | - |")
    for anc in (False, True):
        s = ship(5.84, slow)
        ev = {0.0: Command(0.0, 0.0)}
        if anc:
            ev[30.0] = Command(0.0, 0.0, ANCHOR_LET_GO)
        tr = run(s, 1500.0, 1.0, ev)
        d = distance_run(tr)
        j = np.nonzero(tr.speed < KN)[0]
        reach = f"{d[j[0]]:.0f} (at {tr.t[j[0]]:.0f} s)" if j.size else f"> {d[-1]:.0f} (not reached in 1500 s)"
        i800 = int(np.searchsorted(tr.t, 800.0))
        lines.append(f"| 2: engine stop from 6 kn{', anchor let go at 30 s' if anc else ''} | {tr.u[i800] / KN:.2f} | "
                     f"{d[i800]:.0f} | {reach} |")
    lines += ["", "### S-175, 35 deg turn to port from 9 kn (half ahead), anchor scenarios 3 and 4", "",
              "| case | advance m | transfer m | tactical diameter m | steady speed kn | steady yaw rate deg/s | steady diameter m |",
              "|---|---|---|---|---|---|---|"]
    for case, label in (("normal", "normal turn"), ("dredging", "3: anchor let go 30 s after helm order"),
                        ("dredged", "4: anchor dredged beforehand (600 s), then helm")):
        s = ship(9.0, half)
        run(s, 600.0, 1.0, {0.0: Command(half, 0.0, ANCHOR_LET_GO if case == "dredged" else 0)})
        ev = {0.0: Command(half, math.radians(35.0))}
        if case == "dredging":
            ev[30.0] = Command(half, math.radians(35.0), ANCHOR_LET_GO)
        m = turning_metrics(run(s, 2400.0, 1.0, ev))
        lines.append(f"| {label} (approach {m['approach_speed'] / KN:.2f} kn) | {m['advance']:.0f} | {m['transfer']:.0f} | "
                     f"{m['tactical_diameter']:.0f} | {m['steady_speed'] / KN:.2f} | "
                     f"{math.degrees(m['steady_yaw_rate']):.3f} | {m['steady_diameter']:.0f} |")
    # ---- tug ----
    lines += ["", "### Harbour tug", "", "| quantity | stated | model | kind |", "|---|---|---|---|"]
    tug = load_ship("harbour_tug.yaml")
    tr = run(tug, 300.0, 0.2, {0.0: Command(1.0, 0.0)})
    hook = tug.attachments["towing_hook"]
    tug2 = load_ship("harbour_tug.yaml")
    run(tug2, 120.0, 0.1, {0.0: Command(1.0, 0.0)}, wrenches=lambda v, t: [ExternalWrench(
        np.array([-2e5 * v.state.position[0] - 2e6 * v.state.linear_velocity_body[0], 0, 0]), hook)])
    bp = 2e5 * tug2.state.position[0] / 9806.65
    lines.append(f"| bollard pull ahead, t | 35.4 | {bp:.2f} | calibration: `engine.rated_rpm` chosen for it |")
    lines.append(f"| free-running speed, full ahead, kn | 12.0 | {tr.u[-1] / KN:.2f} | "
                 f"calibration: the resistance's Fn^4 term set for it |")
    t3 = load_ship("harbour_tug.yaml")
    tr3 = run(t3, 300.0, 0.2, {0.0: Command(1.0, math.radians(35.0))})
    m3 = turning_metrics(tr3)
    lines.append(f"| 35 deg turn from rest at full ahead: steady diameter m (/L) | - | {m3['steady_diameter']:.0f} "
                 f"({m3['steady_diameter'] / 24:.1f}) | regression (no published value) |")
    from .vessel import rotation_body_to_world
    for k, tonnes in enumerate((5.0, 10.0, 20.0)):
        t4 = load_ship("harbour_tug.yaml")
        F = tonnes * 9806.65
        run(t4, 200.0, 0.1, wrenches=lambda v, t: [ExternalWrench(
            rotation_body_to_world(v.state.rpy) @ np.array([0.0, F, 0.0]), np.array([0.0, 0.0, hook[2]]))])
        pred = math.degrees(math.asin(min(1.0, F * (hook[2] + 1.5) / (295200 * 9.80665 * 1.2))))
        st = t4.status()
        lines.append(f"| abeam pull {tonnes:.0f} t at hook height: heel deg (GM prediction) / girting ratio, warning | "
                     f"{pred:.2f} | {abs(math.degrees(st.heel)):.2f} / {st.girting_ratio:.2f}, "
                     f"{'WARNING' if st.girting_warning else 'ok'} | "
                     + ("heel: analytic static balance F lever = Delta g GM sin(phi); ratio: regression |" if k == 0
                        else "as above |"))
    return "\n".join(lines)


if __name__ == "__main__":
    print(readme_tables())
