"""The console's order state (ROS-free): keys and joystick axes -> engine order, helm, winch and
anchor orders, always within range whatever comes in (unknown keys do nothing; NaN, infinite or
out-of-range joystick values are ignored or clamped); what a vessel has to be ordered (its ship
file: engine, helm, anchor) and the words the screen puts on orders and angles (port / stbd:
one sign convention, + to port as REP-103, never a bare sign a reader must decode)."""
from __future__ import annotations

import math
from typing import NamedTuple, Optional

ENGINE_STEP = 0.1  # per key press, of full ahead
HELM_STEP_DEG = 5.0  # per key press
JOYSTICK_DEADZONE = 0.05  # |axis| below this is 0 (stick noise)

# key (Textual's key names) -> action
KEYS = {
    "up": "engine+", "w": "engine+", "down": "engine-", "s": "engine-", "x": "engine0",
    "left": "port", "a": "port", "right": "starboard", "d": "starboard", "c": "midships",
    "o": "payout", "i": "heave_in", "h": "hold",
    "l": "let_go", "u": "heave_up",
}
HELP = ("engine: up/w ahead, down/s astern, x stop | helm: left/a port, right/d starboard, c midships | "
        "winch: o pay out, i heave in, h hold | anchor: l let go, u heave up | q quit")


# ship file sections that drive the vessel (tug_dynamics/ships): propellers with an engine,
# azimuth thrusters, a waterjet. Each also steers it (rudders behind the propellers, the
# thrusters' azimuth, the waterjet's nozzle); rudders or steering gear alone steer too.
PROPULSION_KEYS = ("engine", "propellers", "thrusters", "waterjet")
HELM_KEYS = PROPULSION_KEYS + ("rudders", "steering")


class Equipment(NamedTuple):
    """What a vessel has to be ordered and shown: gauges and keys only for these."""
    engine: bool = True  # engine order and shaft speed
    helm: bool = True  # helm order and rudder (or nozzle, azimuth) angle
    anchor: bool = True  # let go / heave up


def equipment(ship: Optional[dict]) -> Equipment:
    """The Equipment of a ship file's mapping (scenario ship_overrides merged in); everything
    for None (no ship file known: nothing is hidden)."""
    if ship is None:
        return Equipment()
    return Equipment(engine=any(ship.get(k) for k in PROPULSION_KEYS),
                     helm=any(ship.get(k) for k in HELM_KEYS), anchor=bool(ship.get("anchor")))


def lacks(key: str, kit: Equipment) -> Optional[str]:
    """What a key orders that the vessel does not have ("engine", "helm", "anchor"), or None."""
    action = KEYS.get(key) or ""
    need = ("engine" if action.startswith("engine") else "helm" if action in ("port", "starboard", "midships")
            else "anchor" if action in ("let_go", "heave_up") else None)
    return need if need is not None and not getattr(kit, need) else None


def engine_words(order: float) -> str:
    """An engine order (-1 .. 1) with two decimals and in percent ahead / astern: "+0.05 (5 % ahead)"."""
    if order == 0.0:
        return "stop"
    return f"{order:+.2f} ({100.0 * abs(order):.0f} % {'ahead' if order > 0 else 'astern'})"


def side_words(angle_deg: float, digits: int = 1, zero: str = "midships") -> str:
    """An angle that is + to port (REP-103) in words: "5.0 deg port", "12.5 deg stbd", or `zero`
    when it rounds to 0 at `digits` decimals."""
    if round(abs(angle_deg), digits) == 0.0 or not math.isfinite(angle_deg):
        return zero if math.isfinite(angle_deg) else "n/a"
    return f"{abs(angle_deg):.{digits}f} deg {'port' if angle_deg > 0 else 'stbd'}"


def turn_words(yaw_rate_deg_min: float) -> str:
    """A rate of turn (deg/min, + to port as a REP-103 yaw rate) in words: "12.3 deg/min to port"."""
    if round(abs(yaw_rate_deg_min), 1) == 0.0:
        return "steady"
    return f"{abs(yaw_rate_deg_min):.1f} deg/min to {'port' if yaw_rate_deg_min > 0 else 'stbd'}"


def _clamp(v: float, lo: float, hi: float) -> float:
    return min(hi, max(lo, v))


class Orders:
    """What the console currently orders one vessel (and the winch of its towline)."""

    def __init__(self, max_helm_deg: float = 35.0, winch_rate: float = 0.5):
        self.max_helm_deg = float(max_helm_deg)
        self.winch_rate = float(winch_rate)  # m/s of a pay-out / heave-in order
        self.engine = 0.0  # -1 .. 1
        self.helm_deg = 0.0  # + to port, within +-max_helm_deg
        self.payout = 0.0  # m/s, + pays out
        self.anchor: Optional[str] = None  # one-shot: "let_go" | "heave_up", cleared when sent
        self.last_key = -1e9  # time.monotonic() of the last key that meant something

    def sync(self, engine: float, helm_deg: float) -> None:
        """Start from the orders the vessel holds, exactly (within range): a held 0.05 stays 0.05
        and a key steps from it; a helm key then sends the held engine order unchanged, so the
        runner does not count it as taking the engine (scenario_runner.order_owner)."""
        if math.isfinite(engine) and math.isfinite(helm_deg):
            self.engine = _clamp(engine, -1.0, 1.0)
            self.helm_deg = _clamp(helm_deg, -self.max_helm_deg, self.max_helm_deg)

    def key(self, key: str) -> Optional[str]:
        """Apply one key; returns what changed ("vessel", "winch") or None for a key that
        means nothing here."""
        action = KEYS.get(key)
        if action is None:
            return None
        if action.startswith("engine"):
            step = {"engine+": ENGINE_STEP, "engine-": -ENGINE_STEP}.get(action)
            self.engine = 0.0 if step is None else round(_clamp(self.engine + step, -1.0, 1.0), 6)
            return "vessel"
        if action in ("port", "starboard", "midships"):
            step = {"port": HELM_STEP_DEG, "starboard": -HELM_STEP_DEG}.get(action)
            self.helm_deg = 0.0 if step is None else _clamp(self.helm_deg + step, -self.max_helm_deg,
                                                            self.max_helm_deg)
            return "vessel"
        if action in ("payout", "heave_in", "hold"):
            self.payout = {"payout": self.winch_rate, "heave_in": -self.winch_rate, "hold": 0.0}[action]
            return "winch"
        self.anchor = action
        return "vessel"

    def joystick(self, throttle: float, rudder: float) -> bool:
        """Stick axes (SDL: -1 .. 1; throttle forward is negative, rudder right is positive):
        engine = -throttle, helm = -rudder x max helm (right = starboard). A non-finite axis is
        ignored, values are clamped, the dead zone is 0; True if the orders changed."""
        changed = False
        if isinstance(throttle, (int, float)) and math.isfinite(throttle):
            t = _clamp(-float(throttle), -1.0, 1.0)
            t = 0.0 if abs(t) < JOYSTICK_DEADZONE else round(t, 2)
            changed |= t != self.engine
            self.engine = t
        if isinstance(rudder, (int, float)) and math.isfinite(rudder):
            r = _clamp(float(rudder), -1.0, 1.0)
            h = 0.0 if abs(r) < JOYSTICK_DEADZONE else round(-r * self.max_helm_deg, 1)
            changed |= h != self.helm_deg
            self.helm_deg = h
        return changed

    def take_anchor(self) -> Optional[str]:
        a, self.anchor = self.anchor, None
        return a


def warnings(girting_ratio: float, girting_threshold: float, tension: float, breaking_load: Optional[float],
             near: float = 0.8) -> list:
    """The console's warnings: the girting ratio at `near` of its threshold or above, the
    tension at `near` of the breaking load or above."""
    out = []
    if girting_threshold > 0 and math.isfinite(girting_ratio) and girting_ratio >= near * girting_threshold:
        out.append(f"GIRTING WARNING: ratio {girting_ratio:.2f} (limit {girting_threshold:.2f})")
    if breaking_load and math.isfinite(tension) and tension >= near * breaking_load:
        out.append(f"TENSION WARNING: {tension / 1e3:.0f} kN, {100 * tension / breaking_load:.0f} % of breaking load")
    return out
