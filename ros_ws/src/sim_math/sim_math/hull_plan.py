"""A vessel's plan shape from its ship file: the one outline the scene draws (sim_plumbing.scene)
and the hull contact pushes on (hull_contact). Body frame, REP-103: x forward, y port, origin
midships on the waterline. A ship (block coefficient below 0.85): elliptic bow over the fore
30 %, parallel middle body, a transom 0.7 of the beam; a barge: a rectangle; a planing hull: a
long elliptic bow. Every shape is convex (the contact's distance test relies on it).
"""
from __future__ import annotations

import math
from typing import Optional, Sequence

import numpy as np

BARGE_BLOCK_COEFFICIENT = 0.85


class HullDimensions:
    """What the scene needs from a ship file (plain numbers, SI)."""

    def __init__(self, length: float, beam: float, draft: float, freeboard: float, kind: str,
                 chine_beam: Optional[float] = None, deadrise: Optional[float] = None,
                 propulsors: Sequence[Sequence[float]] = ()):
        self.length, self.beam, self.draft, self.freeboard = float(length), float(beam), float(draft), float(freeboard)
        self.kind = kind  # ship | barge | planing
        self.chine_beam = float(chine_beam) if chine_beam else 0.88 * self.beam
        self.deadrise = float(deadrise) if deadrise is not None else math.radians(20.0)
        self.propulsors = [tuple(float(c) for c in p) for p in propulsors] or [(-0.48 * self.length, 0.0,
                                                                               -0.5 * self.draft)]

    @staticmethod
    def from_ship_config(cfg: dict) -> "HullDimensions":
        """From a ship file's mapping (overrides merged): displacement or planing_6dof."""
        hull = cfg.get("hull", {})
        if cfg.get("model") == "planing_6dof":
            length = hull["length_overall"]
            jet = cfg.get("waterjet", {}).get("position")
            return HullDimensions(length, hull["beam"], hull["draft"], 0.1 * length, "planing",
                                  chine_beam=hull.get("chine_beam"),
                                  deadrise=math.radians(hull.get("deadrise_deg", 20.0)),
                                  propulsors=[jet] if jet else ())
        length, beam, draft = hull["length"], hull["beam"], hull["draft"]
        rho = cfg.get("water_density", 1025.0)
        cb = hull.get("mass", 0.0) / (rho * length * beam * draft) if hull.get("mass") else 0.7
        # the file's freeboard, else one that puts the deck just below the highest fittings
        heights = [float(p[2]) for p in (cfg.get("attachments") or {}).values()]
        freeboard = cfg.get("roll", {}).get("freeboard") or max(0.5, 0.4 * draft, 0.85 * max(heights, default=0.0))
        props = [p["position"] for p in cfg.get("propellers", []) if "position" in p]
        return HullDimensions(length, beam, draft, freeboard, "barge" if cb >= BARGE_BLOCK_COEFFICIENT else "ship",
                              propulsors=props)


def plan_half_breadth(kind: str, xi: np.ndarray) -> np.ndarray:
    """Half-breadth at the deck as a fraction of the half beam, at xi = x / (L/2) in [-1, 1]."""
    h = np.ones_like(xi)
    if kind == "ship":
        bow = xi > 0.4
        h[bow] = np.sqrt(np.clip(1.0 - ((xi[bow] - 0.4) / 0.6) ** 2, 0.0, 1.0))
        aft = xi < -0.7
        h[aft] = 1.0 - 0.3 * ((-0.7 - xi[aft]) / 0.3) ** 2
    elif kind == "planing":
        bow = xi > 0.1
        h[bow] = np.sqrt(np.clip(1.0 - ((xi[bow] - 0.1) / 0.9) ** 2, 0.0, 1.0))
    return h


def waterline_outline(d: HullDimensions, n: int = 41) -> np.ndarray:
    """The closed plan outline (counter-clockwise, shape (m, 2), first point not repeated): n
    stations along the length, port side forward then starboard side aft; points that coincide
    (a pointed bow) are dropped."""
    xi = np.linspace(-1.0, 1.0, n)
    half = plan_half_breadth(d.kind, xi) * d.beam / 2
    x = xi * d.length / 2
    starboard = np.column_stack((x, -half))             # aft -> forward
    port = np.column_stack((x[::-1], half[::-1]))       # forward -> aft
    pts = np.vstack((starboard, port))
    keep = [0]
    for i in range(1, len(pts)):
        if np.hypot(*(pts[i] - pts[keep[-1]])) > 1e-9:
            keep.append(i)
    if np.hypot(*(pts[keep[-1]] - pts[0])) <= 1e-9:
        keep.pop()
    return pts[keep]
