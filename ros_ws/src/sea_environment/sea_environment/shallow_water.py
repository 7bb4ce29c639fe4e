"""Shallow water: a ship's squat. Pure Python, no ROS.

Squat: ICORELS (1980), as recommended by PIANC (2014) for the bow squat of ships in open
shallow water: S = 2.4 (V/L^2) Fnh^2 / sqrt(1 - Fnh^2), Fnh = U / sqrt(g h), V the displaced
volume; stated for Fnh up to about 0.7 (beyond that this returns the value at 0.7).
"""
from __future__ import annotations

import math

G = 9.80665
FNH_MAX = 0.7


def squat(speed: float, depth: float, length: float, volume: float) -> float:
    """ICORELS bow squat (m) at speed through the water `speed` (m/s) in depth h (m)."""
    if not math.isfinite(depth) or speed == 0.0:
        return 0.0
    fnh = min(abs(speed) / math.sqrt(G * depth), FNH_MAX)
    return 2.4 * volume / (length * length) * fnh * fnh / math.sqrt(1.0 - fnh * fnh)
