"""Initial rope layouts: straight, slack (inextensible catenary), wound on a winch."""
from __future__ import annotations

import math

import numpy as np


def _unit(v, what):
    n = float(np.linalg.norm(v))
    if not math.isfinite(n) or n == 0.0:
        raise ValueError(f"{what}: expected a non-zero finite vector, got {v!r}")
    return np.asarray(v, float) / n


def straight_joints(p_a, p_b, lengths):
    """Joints along the segment a->b, spaced in proportion to the element lengths
    (gaps or overlaps are spread evenly when the span differs from the rope length)."""
    p_a = np.asarray(p_a, float)
    p_b = np.asarray(p_b, float)
    cum = np.concatenate([[0.0], np.cumsum(lengths)])
    s = cum / cum[-1]
    return p_a[None, :] + s[:, None] * (p_b - p_a)[None, :]


def catenary_curve(p_a, p_b, length, sag_direction=(0.0, 0.0, -1.0), n_samples=4001):
    """Dense samples (by arc length) of the inextensible catenary of given length hanging
    from p_a to p_b in the plane spanned by the chord and sag_direction.
    Falls back to the straight segment when length <= chord."""
    p_a = np.asarray(p_a, float)
    p_b = np.asarray(p_b, float)
    up = -_unit(np.asarray(sag_direction, float), "sag_direction")
    S = p_b - p_a
    hgt = float(S @ up)
    dvec = S - hgt * up
    D = float(np.linalg.norm(dvec))
    if D < 1e-9 * max(1.0, length):
        # ends on one vertical: pick any horizontal direction, tiny span
        trial = np.array([1.0, 0.0, 0.0]) if abs(up[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        dhat = trial - (trial @ up) * up
        dhat /= np.linalg.norm(dhat)
        D = 1e-6 * max(1.0, length)
    else:
        dhat = dvec / D
    chord_h = math.sqrt(max(length * length - hgt * hgt, 0.0))
    s = np.linspace(0.0, length, n_samples)
    if chord_h <= D * (1.0 + 1e-12):
        t = s / length
        return p_a[None, :] + t[:, None] * S[None, :]
    target = chord_h / D  # sinh(u)/u = target, u = D/(2a)
    lo, hi = 1e-12, 700.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if math.sinh(mid) / mid < target:
            lo = mid
        else:
            hi = mid
    u = 0.5 * (lo + hi)
    a = D / (2.0 * u)
    x0 = D / 2.0 - a * math.asinh(hgt / (2.0 * a * math.sinh(u)))
    sh0 = math.sinh(-x0 / a)
    x = x0 + a * np.arcsinh(s / a + sh0)
    z = a * np.cosh((x - x0) / a) - a * math.cosh(-x0 / a)
    pts = p_a[None, :] + x[:, None] * dhat[None, :] + z[:, None] * up[None, :]
    pts[-1] = p_b
    return pts


def joints_on_curve(curve, lengths):
    """March along a sampled curve placing joints at exact chord distances."""
    joints = [curve[0].copy()]
    k = 1
    n = len(curve)
    cur = curve[0].copy()
    for l in lengths:
        while k < n and np.linalg.norm(curve[k] - cur) < l:
            k += 1
        if k >= n:  # curve exhausted: continue along the last direction
            tang = curve[-1] - curve[-2]
            tang = tang / np.linalg.norm(tang)
            nxt = cur + l * tang
        else:
            # point on segment curve[k-1] -> curve[k] at distance l from cur
            p0 = curve[k - 1]
            dseg = curve[k] - p0
            w = p0 - cur
            A = dseg @ dseg
            B = 2.0 * (w @ dseg)
            C = w @ w - l * l
            disc = max(B * B - 4 * A * C, 0.0)
            tt = (-B + math.sqrt(disc)) / (2 * A)
            tt = min(max(tt, 0.0), 1.0)
            nxt = p0 + tt * dseg
        joints.append(nxt)
        cur = nxt
    return np.array(joints)


def elements_from_joints(joints, lengths):
    """Centres, axes (pointing to end a) from joint points; element lengths are kept."""
    fr = joints[:-1]
    af = joints[1:]
    d = fr - af
    n = np.linalg.norm(d, axis=1)
    if np.any(n < 1e-12):
        raise ValueError("layout: two consecutive joints coincide; cannot orient an element")
    E = d / n[:, None]
    X = 0.5 * (fr + af)  # gaps/overlaps split evenly between both ends
    return X, E


def polygon_on_catenary(p_a, p_b, lengths, sag_direction=(0.0, 0.0, -1.0)):
    """Joints of a chain of the given link lengths hanging from p_a whose last joint lands
    on p_b: the chords of a catenary are shorter than its arcs, so the curve is made a
    little longer (bisection) until the chord-marched polygon closes."""
    p_a = np.asarray(p_a, float)
    p_b = np.asarray(p_b, float)
    total = float(np.sum(lengths))
    span = float(np.linalg.norm(p_b - p_a))
    if total <= span or len(lengths) == 1:
        return None

    def miss(lc):
        curve = catenary_curve(p_a, p_b, lc, sag_direction)
        j = joints_on_curve(curve, lengths)
        tang = curve[-1] - curve[-2]
        return float((j[-1] - p_b) @ tang / np.linalg.norm(tang)), j

    lo, hi = total, total
    m, best = miss(total)
    if m <= 0.0:
        return best
    for _ in range(60):  # a longer curve is needed: bracket it
        hi *= 1.05
        m, j = miss(hi)
        if m <= 0.0:
            break
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        m, best = miss(mid)
        if m > 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-12 * total:
            break
    best[-1] = p_b
    return best


def close_with_triangle(joints, lengths, p_b, sag_direction=(0.0, 0.0, -1.0)):
    """Re-place the last free joint so that the chain ends exactly on p_b: the last two links
    form a triangle with the chord joints[-3] -> p_b, apex towards the sag direction. Keeps
    the joints unchanged when the triangle does not exist (chord longer than both links)."""
    joints = np.array(joints, float)
    if len(lengths) < 2:
        return joints
    p0 = joints[-3]
    p_b = np.asarray(p_b, float)
    l0, l1 = float(lengths[-2]), float(lengths[-1])
    dvec = p_b - p0
    d = float(np.linalg.norm(dvec))
    if d >= l0 + l1 or d <= abs(l0 - l1) or d == 0.0:
        return joints
    u = dvec / d
    a = (l0 * l0 - l1 * l1 + d * d) / (2.0 * d)
    hh = math.sqrt(max(l0 * l0 - a * a, 0.0))
    g = np.asarray(sag_direction, float)
    w = g - (g @ u) * u
    if np.linalg.norm(w) < 1e-9:  # chord along the sag direction: any perpendicular
        trial = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        w = trial - (trial @ u) * u
    w /= np.linalg.norm(w)
    joints[-2] = p0 + a * u + hh * w
    joints[-1] = p_b
    return joints


def close_with_fabrik(joints, lengths, p_b, iterations=200, tol=1e-9):
    """Move the joints (fixed link lengths, first joint fixed) until the last one lands on
    p_b: FABRIK forward/backward reaching, which keeps the sagging shape of the guess."""
    joints = np.array(joints, float)
    p_a = joints[0].copy()
    p_b = np.asarray(p_b, float)
    lengths = np.asarray(lengths, float)
    if np.linalg.norm(p_b - p_a) > lengths.sum():
        return joints
    n = len(lengths)
    for _ in range(iterations):
        chords = np.linalg.norm(np.diff(joints, axis=0), axis=1)
        if (np.linalg.norm(joints[-1] - p_b) < tol * lengths.sum()
                and np.abs(chords - lengths).max() < tol * lengths.sum()):
            break
        joints[-1] = p_b
        for i in range(n - 1, -1, -1):
            d = joints[i] - joints[i + 1]
            nd = np.linalg.norm(d)
            if nd > 0:
                joints[i] = joints[i + 1] + lengths[i] * d / nd
        joints[0] = p_a
        for i in range(n):
            d = joints[i + 1] - joints[i]
            nd = np.linalg.norm(d)
            if nd > 0:
                joints[i + 1] = joints[i] + lengths[i] * d / nd
    return joints
