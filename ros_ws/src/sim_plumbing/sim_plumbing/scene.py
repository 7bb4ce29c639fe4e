"""The 3D scene of a vessel as visualization_msgs/MarkerArray bytes (no ROS import).

Everything is drawn in the vessel's body frame `<vessel>/base_link` (REP-103: x forward, y port,
z up; origin midships on the static waterline, as the ship files define it) with frame_locked
markers, so the viewer places, heads, heels and trims the vessel with the /tf transform of the
same step: the planing hull shows the trim and heel it runs at, a displacement hull its heel.

Markers (namespace `<vessel>`):
  0 hull: the shell from the ship file's length, beam and draft, as triangles: a ship's hull
    with an elliptic bow, parallel middle body and a transom (block coefficient below 0.85);
    a barge with raked ends (0.85 and above); a planing hull with a deadrise V bottom, chines and
    a keel rising to the bow (planing_6dof files: chine beam and deadrise from the file);
  1 deck: the deck at the freeboard (roll.freeboard of the file, else an estimate);
  2 attachments: a sphere at every attachment point;
  3 the vessel's name above the deck;
  10 + i thrust of propulsor i (propellers or waterjet of the file): an arrow along body x from
    the propulsor, length thrust share x force_scale (astern: pointing aft);
  20 + j force of rope end j, then of hull contact j (hull_contact), on the vessel: an arrow
    from the attachment (contact) point along the force, length |F| x force_scale.
"""
from __future__ import annotations

import math
from typing import Dict, List, Sequence, Tuple

import numpy as np

from sim_math.hull_plan import HullDimensions, plan_half_breadth as _plan
from sim_plumbing import cdr

HULL_COLOR = (0.55, 0.12, 0.10, 1.0)
DECK_COLOR = (0.75, 0.75, 0.72, 1.0)
ATTACHMENT_COLOR = (1.0, 0.85, 0.0, 1.0)
THRUST_COLOR = (0.1, 0.45, 1.0, 1.0)
ROPE_FORCE_COLOR = (1.0, 0.45, 0.0, 1.0)
TEXT_COLOR = (1.0, 1.0, 1.0, 1.0)


def _sections(d: HullDimensions, n: int = 17) -> Tuple[np.ndarray, np.ndarray]:
    """Rings of section points (n stations, each port deck edge -> keel -> starboard deck edge),
    shape (n, m, 3), and the deck edge points (n, 2, 3) (port, starboard)."""
    half_l, half_b, t, f = d.length / 2, d.beam / 2, d.draft, d.freeboard
    xi = np.linspace(-1.0, 1.0, n)
    h = _plan(d.kind, xi)
    rings = []
    for x_frac, hb in zip(xi, h):
        x = x_frac * half_l
        b = hb * half_b
        if d.kind == "planing":
            # keel at -T from the transom to 30 % forward of midships, then rising to the stem
            keel = -t + (t + 0.3 * f) * max(0.0, (x_frac - 0.3) / 0.7) ** 2
            bc = min(b, hb * d.chine_beam / 2)
            chine = min(keel + bc * math.tan(d.deadrise), f)
            port = [(x, b, f), (x, b, max(chine, keel)), (x, bc, chine), (x, 0.0, keel)]
        elif d.kind == "barge":
            rake_bow, rake_stern = 0.12, 0.06  # of the half length
            if x_frac > 1.0 - rake_bow:
                keel = -t * (1.0 - x_frac) / rake_bow
            elif x_frac < -1.0 + rake_stern:
                keel = -t * (1.0 + x_frac) / rake_stern
            else:
                keel = -t
            port = [(x, b, f), (x, b, 0.0), (x, b, keel), (x, 0.0, keel)]
        else:
            keel = -t
            port = [(x, b, f), (x, b, 0.0), (x, 0.96 * b, -0.6 * t), (x, 0.75 * b, -t), (x, 0.0, -t)]
        starboard = [(px, -py, pz) for px, py, pz in reversed(port[:-1])]
        rings.append(port + starboard)
    rings = np.array(rings, float)
    return rings, rings[:, [0, -1], :]


def _strip_triangles(a: np.ndarray, b: np.ndarray) -> List[np.ndarray]:
    """Triangles joining two polylines of equal length (quads split in two)."""
    tris = []
    for i in range(len(a) - 1):
        tris += [a[i], b[i], b[i + 1], a[i], b[i + 1], a[i + 1]]
    return tris


def hull_triangles(d: HullDimensions) -> Tuple[np.ndarray, np.ndarray]:
    """(shell triangles (3k, 3), deck triangles (3j, 3)) in the body frame."""
    rings, edges = _sections(d)
    shell: List[np.ndarray] = []
    for i in range(len(rings) - 1):
        shell += _strip_triangles(rings[i], rings[i + 1])
    for ring in (rings[0], rings[-1]):  # the end faces, closed by the deck edge line
        centre = ring.mean(axis=0)
        for i in range(len(ring) - 1):
            shell += [centre, ring[i], ring[i + 1]]
    deck: List[np.ndarray] = []
    for i in range(len(edges) - 1):
        deck += _strip_triangles(edges[i], edges[i + 1])
    return np.array(shell, float), np.array(deck, float)


class VesselScene:
    """Marker bytes of one vessel; the hull is laid out once, arrows change per call."""

    def __init__(self, vessel: str, dims: HullDimensions, attachments: Dict[str, Sequence[float]]):
        self.vessel = vessel
        self.frame = f"{vessel}/base_link"
        self.dims = dims
        shell, deck = hull_triangles(dims)
        size = max(0.3, 0.015 * dims.length)
        pts = np.array([attachments[n] for n in sorted(attachments)], float).reshape(-1, 3)
        self._fixed = [
            cdr.MarkerSpec(vessel, 0, cdr.MARKER_TRIANGLE_LIST, (1.0, 1.0, 1.0), HULL_COLOR, shell, frame_locked=True),
            cdr.MarkerSpec(vessel, 1, cdr.MARKER_TRIANGLE_LIST, (1.0, 1.0, 1.0), DECK_COLOR, deck, frame_locked=True),
            cdr.MarkerSpec(vessel, 2, cdr.MARKER_SPHERE_LIST, (size, size, size), ATTACHMENT_COLOR, pts,
                           frame_locked=True),
            cdr.MarkerSpec(vessel, 3, cdr.MARKER_TEXT, (0.0, 0.0, max(1.0, 0.06 * dims.length)), TEXT_COLOR,
                           pose=(0.0, 0.0, dims.freeboard + max(2.0, 0.1 * dims.length), 0.0, 0.0, 0.0, 1.0),
                           text=vessel, frame_locked=True),
        ]
        self._shaft = max(0.15, 0.012 * dims.length)
        self._template = cdr.MarkerArrayTemplate(self.frame, self._fixed)

    def _arrow(self, marker_id: int, start: Sequence[float], vector: Sequence[float], color) -> cdr.MarkerSpec:
        start = np.asarray(start, float)
        return cdr.MarkerSpec(self.vessel, marker_id, cdr.MARKER_ARROW,
                              (self._shaft, 2.0 * self._shaft, 3.0 * self._shaft), color,
                              np.array([start, start + np.asarray(vector, float)]), frame_locked=True)

    def markers(self, stamp_ns: int, thrust: float, rope_forces: Sequence[Tuple[Sequence[float], Sequence[float]]],
                force_scale: float) -> bytes:
        """thrust: total propulsion thrust along body x, N (shared equally by the propulsors);
        rope_forces: (attachment point, force in body axes N) per rope end; force_scale m/N."""
        arrows = []
        share = thrust / len(self.dims.propulsors)
        for i, p in enumerate(self.dims.propulsors):
            arrows.append(self._arrow(10 + i, p, (share * force_scale, 0.0, 0.0), THRUST_COLOR))
        for j, (point, force) in enumerate(rope_forces):
            arrows.append(self._arrow(20 + j, point, np.asarray(force, float) * force_scale, ROPE_FORCE_COLOR))
        return self._template.encode(stamp_ns, arrows)
