"""Wind loads on a vessel's above-water hull after W. Blendermann (1994), "Parameter
identification of wind loads on ships", J. Wind Eng. Ind. Aerodyn. 51, 339-351: a four-parameter
model fitted to wind-tunnel data of 17 ship types (his Table 2, also Fossen, Handbook of Marine
Craft Hydrodynamics and Motion Control, 2nd ed. 2021, Table 10.4). Numba kernels with Python wrappers, no ROS.

With gamma the angle the apparent wind comes FROM, measured from the bow (0 = head wind,
pi = from astern; the coefficients are symmetric port / starboard), A_F and A_L the frontal and
lateral projected areas above the waterline, L_oa the length overall:

    D(gamma) = 1 - delta/2 (1 - CD_l/CD_t) sin^2(2 gamma),   CD_l = CD_l,AF A_F / A_L
    C_X = -CD_l,AF(gamma) cos(gamma) / D        X = 1/2 rho_a V^2 A_F C_X
    C_Y =  CD_t sin(gamma) / D                  Y = 1/2 rho_a V^2 A_L C_Y
    C_N = [s_L/L_oa - 0.18 (gamma - pi/2)] C_Y  N = 1/2 rho_a V^2 A_L L_oa C_N
    C_K = kappa s_H/H_M C_Y,  H_M = A_L / L_oa  K = 1/2 rho_a V^2 A_L H_M C_K

CD_l,AF takes its bow value for head winds (gamma < pi/2) and its stern value otherwise.
s_L is the lateral area's centroid forward of midship, s_H its height above the waterline.
The side force therefore acts at x = s_L - 0.18 (gamma - pi/2) L_oa (moving towards the end the
wind comes from) and at height kappa s_H: `wind_wrench_body` returns the force and that point,
so a model with roll also feels the heeling moment.

Body axes here are REP-103 (x forward, y port); the apparent wind angle is + when the wind
comes from port (sea_environment.wind.apparent_wind), so a port wind pushes to starboard.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Dict, Tuple

from numba import njit

RHO_AIR = 1.225  # kg/m^3, ISA sea level, 15 C

# Blendermann (1994) Table 2: CD_t, CD_l,AF bow, CD_l,AF stern, delta, kappa
BLENDERMANN_TABLE: Dict[str, Tuple[float, float, float, float, float]] = {
    "car_carrier":              (0.95, 0.55, 0.60, 0.80, 1.2),
    "cargo_vessel_loaded":      (0.85, 0.65, 0.55, 0.40, 1.7),
    "cargo_vessel_container_on_deck": (0.85, 0.55, 0.50, 0.40, 1.4),
    "container_ship_loaded":    (0.90, 0.55, 0.55, 0.40, 1.4),
    "destroyer":                (0.85, 0.60, 0.65, 0.65, 1.1),
    "diving_support_vessel":    (0.90, 0.60, 0.80, 0.55, 1.7),
    "drilling_vessel":          (1.00, 0.85, 0.925, 0.10, 1.7),  # CD_l,AF 0.70-1.00 / 0.75-1.10: mid values
    "ferry":                    (0.90, 0.45, 0.50, 0.80, 1.1),
    "fishing_vessel":           (0.95, 0.70, 0.70, 0.40, 1.1),
    "lng_tanker":               (0.70, 0.60, 0.65, 0.50, 1.1),
    "offshore_supply_vessel":   (0.90, 0.55, 0.80, 0.55, 1.2),
    "passenger_liner":          (0.90, 0.40, 0.40, 0.80, 1.2),
    "research_vessel":          (0.85, 0.55, 0.65, 0.60, 1.4),
    "speed_boat":               (0.90, 0.55, 0.60, 0.60, 1.1),
    "tanker_loaded":            (0.70, 0.90, 0.55, 0.40, 3.1),
    "tanker_in_ballast":        (0.70, 0.75, 0.55, 0.40, 2.2),
    "tender":                   (0.85, 0.55, 0.55, 0.65, 1.1),
}


@dataclasses.dataclass(frozen=True)
class Windage:
    """A vessel's above-water particulars (the ship file's ``windage`` section), SI.

    ship_type: a key of BLENDERMANN_TABLE. frontal_area A_F, lateral_area A_L (m^2);
    centroid_x s_L (m, lateral area centroid forward of the body origin); centroid_height s_H
    (m above the waterline); length_overall L_oa (m)."""
    ship_type: str
    frontal_area: float
    lateral_area: float
    centroid_x: float
    centroid_height: float
    length_overall: float

    def __post_init__(self):
        if self.ship_type not in BLENDERMANN_TABLE:
            raise ValueError(f"windage.type: {self.ship_type!r} is not one of Blendermann's types "
                             f"({', '.join(sorted(BLENDERMANN_TABLE))})")
        for key in ("frontal_area", "lateral_area", "centroid_height", "length_overall"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"windage.{key}: {value!r} must be a finite number > 0")
        if not (math.isfinite(self.centroid_x) and abs(self.centroid_x) <= 0.5 * self.length_overall):
            raise ValueError(f"windage.centroid_x: {self.centroid_x!r} m must lie within half the length overall "
                             f"({0.5 * self.length_overall:g} m) of the reference point")

    def parameters(self) -> Tuple[float, ...]:
        """Blendermann's five coefficients of the type, then the five particulars: the argument
        list of the `blendermann` and `wind_wrench` kernels."""
        return (*BLENDERMANN_TABLE[self.ship_type], self.frontal_area, self.lateral_area, self.centroid_x,
                self.centroid_height, self.length_overall)

    @staticmethod
    def from_config(section: dict) -> "Windage":
        """From a ship file's ``windage`` mapping (keys: type, frontal_area, lateral_area,
        centroid_x, centroid_height, length_overall); errors name the key."""
        if not isinstance(section, dict):
            raise ValueError(f"windage: expected a mapping, got {type(section).__name__}")
        keys = ("type", "frontal_area", "lateral_area", "centroid_x", "centroid_height", "length_overall")
        unknown = sorted(set(section) - set(keys))
        if unknown:
            raise ValueError(f"windage.{unknown[0]}: unknown key (expected {', '.join(keys)})")
        missing = [k for k in keys if k not in section]
        if missing:
            raise ValueError(f"windage.{missing[0]}: required key is missing")
        for k in keys[1:]:
            v = section[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ValueError(f"windage.{k}: expected a number, got {v!r}")
        if not isinstance(section["type"], str):
            raise ValueError(f"windage.type: expected a Blendermann ship type name, got {section['type']!r}")
        return Windage(section["type"], *(float(section[k]) for k in keys[1:]))


def blendermann_coefficients(gamma: float, w: Windage) -> Tuple[float, float, float, float]:
    """(C_X, C_Y, C_K, C_N) for a wind from gamma (rad, 0 = from ahead, 0 <= gamma <= pi)."""
    return blendermann(gamma, *w.parameters())


@njit(cache=True)
def blendermann(gamma, cdt, cdl_bow, cdl_stern, delta, kappa, frontal_area, lateral_area, centroid_x,
                centroid_height, length_overall):
    """blendermann_coefficients on Windage.parameters(), as a kernel."""
    cdl_af = cdl_bow if gamma <= 0.5 * math.pi else cdl_stern
    cdl = cdl_af * frontal_area / lateral_area
    den = 1.0 - 0.5 * delta * (1.0 - cdl / cdt) * math.sin(2.0 * gamma) ** 2
    cx = -cdl_af * math.cos(gamma) / den
    cy = cdt * math.sin(gamma) / den
    hm = lateral_area / length_overall
    ck = kappa * centroid_height / hm * cy
    cn = (centroid_x / length_overall - 0.18 * (gamma - 0.5 * math.pi)) * cy
    return cx, cy, ck, cn


def wind_wrench_body(speed: float, angle: float, w: Windage,
                     rho_air: float = RHO_AIR) -> Tuple[float, float, float, float, float]:
    """The wind's force on the vessel in body axes (REP-103) and its point of action.

    speed, angle: the apparent wind (m/s; rad, where it comes FROM, + from port, in (-pi, pi]).
    Returns (X, Y, x_point, z_point, N): force components (N), the point (m, body x, height
    above the waterline) where the side force acts (Blendermann's centre of pressure), and the
    yaw moment N about the body origin (N m; = x_point * Y, given for checks)."""
    return wind_wrench(speed, angle, rho_air, *w.parameters())


@njit(cache=True)
def wind_wrench(speed, angle, rho_air, cdt, cdl_bow, cdl_stern, delta, kappa, frontal_area, lateral_area,
                centroid_x, centroid_height, length_overall):
    """wind_wrench_body on Windage.parameters(), as a kernel."""
    cx, cy, ck, cn = blendermann(abs(angle), cdt, cdl_bow, cdl_stern, delta, kappa, frontal_area, lateral_area,
                                 centroid_x, centroid_height, length_overall)
    q = 0.5 * rho_air * speed * speed
    side = -1.0 if angle >= 0.0 else 1.0   # a wind from port pushes to starboard (-y)
    fx = q * frontal_area * cx
    fy = side * q * lateral_area * cy
    x_point = cn / cy * length_overall if cy != 0.0 else centroid_x
    hm = lateral_area / length_overall
    z_point = ck / cy * hm if cy != 0.0 else centroid_height
    return fx, fy, x_point, z_point, x_point * fy
