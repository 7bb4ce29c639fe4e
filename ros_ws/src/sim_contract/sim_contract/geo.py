"""Geography and units at the human and equipment edge (ROS-free).

Inside the simulator everything is SI and REP-103: the world frame `map` is a flat ENU plane
(x east, y north, metres) and yaw is counter-clockwise from east. People and bridge equipment
use latitude / longitude (WGS-84), compass headings (deg true, clockwise from north) and knots.
This module is the one place where they meet:

- ENU metres <-> WGS-84 through pymap3d (the map plane is the local tangent plane at the
  scenario's origin, `enu2geodetic` / `geodetic2enu` on the WGS-84 ellipsoid);
- compass heading <-> yaw: compass = (90 - yaw_deg) mod 360 (sim_math.trials.compass_deg);
- knots <-> m/s: 1 kn = 1852 m / 3600 s exactly.
"""
from __future__ import annotations

import math
from typing import NamedTuple, Tuple

import pymap3d

from sim_math.trials import compass_deg

KNOT = 1852.0 / 3600.0  # m/s per knot (international nautical mile, exact)


class Origin(NamedTuple):
    """The geographic position of the map origin (x = y = 0, still-water surface z = 0)."""
    latitude: float  # deg north, WGS-84
    longitude: float  # deg east, WGS-84
    height: float = 0.0  # m above the WGS-84 ellipsoid of the still-water surface there


# Default map origin: the Port of Rotterdam, in the Maasmond (the harbour entrance between the
# breakwaters of the Nieuwe Waterweg and the Maasgeul), 51 deg 58.8' N, 4 deg 03.0' E.
DEFAULT_ORIGIN = Origin(51.98, 4.05, 0.0)


def enu_to_geodetic(x: float, y: float, origin: Origin, z: float = 0.0) -> Tuple[float, float, float]:
    """(latitude deg, longitude deg, height m) of a map point (x east, y north, z up, metres)."""
    lat, lon, h = pymap3d.enu2geodetic(x, y, z, origin.latitude, origin.longitude, origin.height, deg=True)
    return float(lat), float(lon), float(h)


def geodetic_to_enu(latitude: float, longitude: float, origin: Origin, height: float = None
                    ) -> Tuple[float, float, float]:
    """Map coordinates (x east, y north, z up, metres) of a WGS-84 position; height defaults to
    the origin's (a point on the water surface)."""
    h = origin.height if height is None else height
    e, n, u = pymap3d.geodetic2enu(latitude, longitude, h, origin.latitude, origin.longitude, origin.height,
                                   deg=True)
    return float(e), float(n), float(u)


def yaw_from_compass(compass: float) -> float:
    """REP-103 yaw (rad, counter-clockwise from east) of a compass heading (deg true)."""
    return math.radians(90.0 - compass)


def yaw_deg_from_compass(compass: float) -> float:
    """The same in degrees, in (-270, 90]: within the +-360 deg the scenario format accepts."""
    return 90.0 - compass


def knots(speed: float) -> float:
    """m/s -> kn."""
    return speed / KNOT


def metres_per_second(kn: float) -> float:
    """kn -> m/s."""
    return kn * KNOT


def course_over_ground(v_east: float, v_north: float) -> float:
    """Course over ground, deg true in [0, 360), of a velocity in the map frame (0 when at rest)."""
    return math.degrees(math.atan2(v_east, v_north)) % 360.0


def rate_of_turn(yaw_rate: float) -> float:
    """Rate of turn as NMEA and AIS give it, deg/min, positive turning to starboard (clockwise),
    of a REP-103 yaw rate (rad/s, positive counter-clockwise)."""
    return -math.degrees(yaw_rate) * 60.0


__all__ = ["KNOT", "Origin", "DEFAULT_ORIGIN", "enu_to_geodetic", "geodetic_to_enu", "compass_deg",
           "yaw_from_compass", "yaw_deg_from_compass", "knots", "metres_per_second", "course_over_ground",
           "rate_of_turn"]
