"""The manoeuvres of Yoon & Kang's section 4 (planing hull), run on a PlaningHull; key figures
for PLANING.md.

    python -m tug_dynamics.planing_manoeuvres [ship_file]   # prints the markdown tables

Sign conventions as vessel.py: steering_angle > 0 turns to port, so the paper's starboard
turn with a 10 deg bucket (its 4.2) is steering_angle = -10 deg. Roll > 0 is starboard side
down (REP-103), i.e. inward in a starboard turn. Trim in the tables is bow-up positive
(Savitsky's tau = -pitch).
"""
from __future__ import annotations

import math
import os
import sys
from typing import Dict, Optional

import numpy as np

from sim_math.turning import turning_measures
from tug_dynamics.planing import KNOT, PlaningHull, load
from tug_dynamics.vessel import Command

DT = 0.05
DEFAULT_SHIP = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                            "ships", "planing_40ft.yaml")


def _record(model: PlaningHull, t: float, log: Dict[str, list]) -> None:
    s, st = model.state, model.status()
    log["t"].append(t)
    log["x"].append(s.position[0])
    log["y"].append(s.position[1])
    log["rise"].append(s.position[2])
    log["roll"].append(s.rpy[0])
    log["pitch"].append(s.rpy[1])
    log["yaw"].append(s.rpy[2])
    log["u"].append(s.linear_velocity_body[0])
    log["v"].append(s.linear_velocity_body[1])
    log["r"].append(s.angular_velocity_body[2])
    log["thrust"].append(st.thrust)
    log["lift"].append(st.lift)
    log["throttle"].append(st.throttle)
    log["bucket"].append(st.steering_angle)


def run(model: PlaningHull, orders, duration: float, dt: float = DT) -> Dict[str, np.ndarray]:
    """orders: list of (time, engine_order or None, steering_angle or None), sorted by time."""
    keys = ("t", "x", "y", "rise", "roll", "pitch", "yaw", "u", "v", "r", "thrust", "lift", "throttle", "bucket")
    log: Dict[str, list] = {k: [] for k in keys}
    orders = list(orders)
    eo, st = model.command.engine_order, model.command.steering_angle
    n = int(round(duration / dt))
    _record(model, 0.0, log)
    for i in range(n):
        t = i * dt
        while orders and orders[0][0] <= t + 1e-9:
            _, e, s = orders.pop(0)
            eo = eo if e is None else e
            st = st if s is None else s
            model.set_command(Command(eo, st))
        model.step(dt)
        _record(model, (i + 1) * dt, log)
    return {k: np.asarray(v) for k, v in log.items()}


def _first_time(t, cond) -> float:
    idx = np.flatnonzero(cond)
    return float(t[idx[0]]) if idx.size else float("nan")


def acceleration(path: str = DEFAULT_SHIP, duration: float = 90.0) -> Dict:
    """From rest, full throttle ahead at t = 0 (paper Fig. 11)."""
    m = load(path)
    h = run(m, [(0.0, 1.0, 0.0)], duration)
    ss = m.steady_state(m.full_speed)
    fig = {
        "t_10kn": _first_time(h["t"], h["u"] >= 10 * KNOT),
        "t_20kn": _first_time(h["t"], h["u"] >= 20 * KNOT),
        "t_30kn": _first_time(h["t"], h["u"] >= 30 * KNOT),
        "max_trim_deg": float(np.degrees(-h["pitch"]).max()),
        "u_at_max_trim": float(h["u"][np.argmax(-h["pitch"])]),
        "final_speed_kn": float(h["u"][-1] / KNOT),
        "final_trim_deg": float(-math.degrees(h["pitch"][-1])),
        "final_rise": float(h["rise"][-1]),
        "steady_trim_deg": ss["trim_deg"], "steady_rise": ss["rise"],
        "distance_60s": float(np.interp(60.0, h["t"], h["x"])),
    }
    return {"history": h, "figures": fig}


def deceleration_backing(path: str = DEFAULT_SHIP, t_back: float = 30.0, duration: float = 70.0) -> Dict:
    """Full speed, throttle to zero at t = 0, full astern at t_back (paper Fig. 12)."""
    m = load(path)
    m.set_steady_run(m.full_speed)
    h = run(m, [(0.0, 0.0, 0.0), (t_back, -1.0, None)], duration)
    back = h["t"] >= t_back
    fig = {
        "u0_kn": float(h["u"][0] / KNOT),
        "t_to_10kn": _first_time(h["t"], h["u"] <= 10 * KNOT),
        "t_to_5kn": _first_time(h["t"], h["u"] <= 5 * KNOT),
        "u_at_astern_order": float(np.interp(t_back, h["t"], h["u"])),
        "t_u_zero": _first_time(h["t"], h["u"] <= 0.0),
        "head_reach": float(h["x"].max()),
        "astern_speed": float(h["u"][-1]),
        "astern_trim_deg": float(-math.degrees(h["pitch"][-1])),
        "max_lift_astern": float(np.abs(h["lift"][back & (h["u"] < 0)]).max(initial=0.0)),
        "trim_at_t0_deg": float(-math.degrees(h["pitch"][0])),
    }
    return {"history": h, "figures": fig}


def turn(path: str = DEFAULT_SHIP, speed: float = 12.0, bucket_deg: float = -10.0,
         duration: float = 150.0) -> Dict:
    """Steady run at `speed`, then the bucket to `bucket_deg` (interface sign; -10 = starboard).

    The turning measures are sim_math.turning's (helm order at t0 = 0; the steady values over
    its steady window, the last full revolution but not the first 180 deg; NaN if the turn is
    shorter than 270 deg): advance, transfer, tactical diameter, steady diameter (circle fit),
    steady speed U and speed loss U / U0, yaw rate, drift angle atan2(-v, u) (REP-103 sign:
    negative = bow inside in a starboard turn). Roll and trim are averaged over the same window."""
    m = load(path)
    m.set_steady_run(speed)
    h = run(m, [(0.0, None, math.radians(bucket_deg))], duration)
    tm = turning_measures(h["t"], h["x"], h["y"], h["yaw"], h["u"], h["v"], h["r"], 0.0)
    steady = h["t"] >= tm["steady_t_start"]          # empty (NaN start) if the turn is too short

    def steady_mean_deg(values) -> float:
        return float(np.degrees(values[steady].mean())) if steady.any() else float("nan")

    fig = {
        "u0": tm["approach_speed"],
        "steady_speed": tm["steady_speed"],
        "speed_loss_pct": 100.0 * (1.0 - tm["speed_loss"]),
        "steady_r_deg_s": math.degrees(tm["steady_yaw_rate"]),
        "steady_roll_deg": steady_mean_deg(h["roll"]),
        "max_roll_deg": float(np.degrees(np.abs(h["roll"])).max()),
        "steady_trim_deg": -steady_mean_deg(h["pitch"]),
        "steady_drift_deg": math.degrees(tm["steady_drift_angle"]),
        "advance": tm["advance"],
        "transfer": tm["transfer"],
        "tactical_diameter": tm["tactical_diameter"],
        "t_180": tm["time_to_180"],
        "diameter": tm["steady_diameter"],
        "diameter_kinematic": tm["steady_diameter_kinematic"],
    }
    return {"history": h, "figures": fig, "turning": tm}


def zigzag(path: str = DEFAULT_SHIP, speed: float = 12.0, bucket_deg: float = 10.0, every: float = 5.0,
           changes: int = 9, tail: float = 5.0) -> Dict:
    """Bucket +-bucket_deg, reversed every `every` s, `changes` orders (first to starboard)."""
    m = load(path)
    m.set_steady_run(speed)
    orders = [(k * every, None, math.radians(-bucket_deg if k % 2 == 0 else bucket_deg)) for k in range(changes)]
    duration = changes * every + tail
    h = run(m, orders, duration)
    roll = np.degrees(h["roll"])
    # peaks per half-cycle after the first leg
    peaks = []
    for k in range(1, changes):
        sel = (h["t"] >= k * every) & (h["t"] < (k + 1) * every)
        peaks.append(float(roll[sel][np.argmax(np.abs(roll[sel]))]))
    steady_part = h["t"] >= every
    fig = {
        "roll_peaks_deg": peaks,
        # the first half-cycle starts from the straight run (a transient): the amplitude is
        # that of the periodic part, from the second half-cycle on
        "first_roll_peak_deg": peaks[0],
        "roll_amplitude_deg": float(np.mean(np.abs(peaks[1:]))),
        "roll_rms_deg": float(np.sqrt(np.mean(roll[steady_part] ** 2))),
        "max_yaw_excursion_deg": float(np.degrees(np.abs(np.unwrap(h["yaw"]) - h["yaw"][0])).max()),
        "min_u": float(h["u"].min()), "u0": float(h["u"][0]),
        "speed_loss_pct": float(100.0 * (1.0 - h["u"].min() / h["u"][0])),
    }
    return {"history": h, "figures": fig}


def main(argv: Optional[list] = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    path = argv[0] if argv else DEFAULT_SHIP
    a = acceleration(path)["figures"]
    d = deceleration_backing(path)["figures"]
    t = turn(path)["figures"]
    z = zigzag(path)["figures"]
    print("| Acceleration from rest, full throttle | value |\n|---|---|")
    for k, v in a.items():
        print(f"| {k} | {v:.3f} |")
    print("\n| Deceleration (throttle 0 at t=0) and backing (full astern at 30 s) | value |\n|---|---|")
    for k, v in d.items():
        print(f"| {k} | {v:.3f} |")
    print("\n| Turn from 12 m/s, bucket 10 deg to starboard | value |\n|---|---|")
    for k, v in t.items():
        print(f"| {k} | {v:.3f} |")
    print("\n| Zig-zag from 12 m/s, bucket +-10 deg every 5 s, 9 orders | value |\n|---|---|")
    for k, v in z.items():
        print(f"| {k} | {', '.join(f'{p:.2f}' for p in v) if isinstance(v, list) else f'{v:.3f}'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
