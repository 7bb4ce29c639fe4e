#!/usr/bin/env python3
"""Hydrodynamic data of the displacement hulls (ships/*.yaml, `model: displacement`) with the
boundary element code Capytaine 3.0 (linear potential flow, zero forward speed, deep water):
added mass, radiation damping, excitation force (Froude-Krylov + diffraction), hydrostatics,
6-DOF motion RAOs and the mean wave drift force coefficients, per wave frequency and relative
heading. One file per ship: ros_ws/src/tug_dynamics/ships/hydro/<ship>.npz (format below), read
at run time by tug_dynamics.wave_response (numpy only; this script alone needs capytaine).

    scripts/hydro_data.py                 # every displacement hull, the standard mesh
    scripts/hydro_data.py --ship asd_tug  # one hull (repeatable)
    scripts/hydro_data.py --coarse        # coarse mesh and grids (a quick look, the tests)
    scripts/hydro_data.py --out /tmp/h    # elsewhere

Geometry (from the ship file's hull.length L, hull.beam B, hull.draft T, hull.mass m and
water_density rho; block coefficient Cb = m / (rho L B T), the files' own definition):
- barges (box_barge_000, barge_002_model, barge_002_full: hull.form lowspeed/polynomial with
  Cb >= 0.85): a rectangular box L x B with the draft T_box = m / (rho L B) = Cb T, so the box
  floats at equilibrium with the file's mass and keeps the full L x B waterplane of a raked-end
  barge (the rake removes volume below the waterline, not waterplane).
- ships (harbour_tug, asd_tug, s175_003): a simple parametric hull of the file's L, B, T and Cb:
  half-breadth y(x, z) = B/2 (1 - |2x/L|^p(z)) (1 - |z/T|^q), z in [-T, 0], q = 9 (midship
  coefficient Cm = q / (q + 1) = 0.90, a round bilge; wall-sided at the waterline) and the
  waterline exponent varying with depth, p(z) = p_k + (p_w - p_k) (1 - |z|/T)^3, so the
  waterplane can be full (Cwp = p_w / (p_w + 1)) while the ends below are fine (V-shaped).
  p_w: where the file has roll.bm (the tugs), the waterline whose I_T = (2/3) int y^3 dx gives
  that BM (the simulator's own roll model's figure); else Cwp = (1 + 2 Cb) / 3 (Schneekluth &
  Bertram 1998, U-sections). p_k: solved (bisection) so the mesh displaces m / rho. The hull is
  shifted along x so its centre of buoyancy is at the file's x_g (trimmed equilibrium).
Both are symmetric port/starboard (xOz): only relative headings 0..180 deg are solved; 180..360
are mirrored (sway, roll, yaw, drift Y and N change sign). An interior lid on the waterplane
removes the irregular frequencies.

Mass properties (the ship files give m, x_g and the yaw radius of gyration; the rest chosen):
- the vertical centre of gravity: roll.z_g of the file when it has a `roll:` section (the two
  tugs, the simulator's own roll model); barges z_g = 0 (KG = T: G on the still waterline);
  the S-175 (no roll section) G placed for GM_T = 1.0 m (a loaded container ship's order).
- roll radius of gyration: roll.radius_of_gyration of the file, else 0.35 B; pitch 0.25 L;
  yaw: hull.yaw_radius_of_gyration; no products of inertia.
- viscous roll damping (potential roll damping alone gives an unbounded resonance): a linear
  B44v = 2 zeta sqrt(C44 (I44 + A44(w_n))) added to the potential damping, zeta = the file's
  roll.damping_ratio, else 0.10 for the square-bilged boxes (vortex shedding at the bilges) and
  0.05 for the round-bilged ship form; w_n the undamped roll natural frequency (A44 at w_n).
Motions are about the reference point (0, 0, 0): midships on the centreline at the still
waterline (body axes REP-103: x forward, y port, z up); rotations in rad.

Grids: w from 0.2 rad/s to max(2.5, 2.5 sqrt(45 m / L)) rad/s (small hulls, e.g. the 1/9 tank
model, get the Froude-scaled range), 30 values (coarse 12); relative heading beta 0..360 deg
step 15 deg (coarse 30 deg). Panel size h = L / 40 (coarse L / 20) and at most h across the
draft (ships: at least 10 panels, coarse 6, from waterline to keel); the mesh is adequate for
wavelengths above ~6 h (the RAOs at shorter waves are small).

Mean wave drift (surge, sway force and yaw moment per unit amplitude squared): Maruo's (1960)
far-field formula (momentum flux through a control surface at infinity; Newman 1967 for the yaw
moment), evaluated from Capytaine's Kochin functions of the diffracted and radiated (times the
RAO) waves by capytaine.post_pro.far_field_mean_drift_force. Far field rather than the
near-field (pressure integration) method because it needs only the Kochin functions, converges
faster with the panel size and does not need the relative wave elevation along the waterline,
which a coarse mesh gets poorly (Faltinsen 1990 ch. 5; Newman 1977 ch. 6). Only the diagonal
(one frequency, one direction) terms are kept: the mean drift in a sea of many components is
sum_i a_i^2 D(w_i, beta_i) (Faltinsen 1990 ch. 5, Newman's approximation aside).

Conventions (e^{-i w t} time dependence, Capytaine's): the incident wave is
eta = Re(a exp(i (k (x cos beta + y sin beta) - w t))) in body axes, beta the direction the waves
travel TOWARDS measured counter-clockwise from the body's +x: beta = 180 deg head seas, 0
following seas, 90 deg waves travelling towards port (coming from starboard). A response is
Re(a RAO exp(i (k (x cos beta + y sin beta) - w t))) = a |RAO| cos(theta + phase), theta the
wave phase at the reference point: the RAO phase is the lead over the wave crest there.

File format (numpy .npz, all arrays; FORMAT_VERSION 1):
  format_version ()        int, 1
  ship ()                  str, the ship file's name
  units ()                 str, JSON mapping each key to its unit
  notes ()                 str, JSON: the assumptions above with the numbers used
  mesh_faces ()            int, panels of the hull (without the lid); mesh_panel_size () m
  rho, g, mass ()          kg/m^3, m/s^2, kg
  length, beam, draft, draft_mesh ()   m (draft_mesh: the box's Cb T for barges)
  displaced_volume ()      m^3 of the mesh
  center_of_gravity (3)    m, body axes from the reference point
  omega (nw)               rad/s, increasing
  heading (nb)             rad, beta = 0 .. 2 pi (excluded), uniform
  dofs (6)                 str: surge, sway, heave, roll, pitch, yaw
  inertia_matrix (6, 6), hydrostatic_stiffness (6, 6), viscous_damping (6, 6)   SI
  added_mass (nw, 6, 6), radiation_damping (nw, 6, 6)                           SI
  excitation_amplitude, excitation_phase (nw, nb, 6)       N/m, N m/m; rad
  froude_krylov_amplitude, froude_krylov_phase (nw, nb, 6) N/m, N m/m; rad
  rao_amplitude (nw, nb, 6)  m/m (surge, sway, heave), rad/m (roll, pitch, yaw)
  rao_phase (nw, nb, 6)      rad
  drift (nw, nb, 3)          mean drift X, Y (N/m^2) and N (N m/m^2) per unit amplitude^2, body axes
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHIPS = os.path.join(ROOT, "ros_ws", "src", "tug_dynamics", "ships")
for _pkg in ("tug_dynamics", "sim_math", "sea_environment"):
    sys.path.insert(0, os.path.join(ROOT, "ros_ws", "src", _pkg))

FORMAT_VERSION = 1
G = 9.80665
DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")
CPT_DOFS = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
CM_SHIP = 0.90            # midship coefficient of the parametric ship form
BOX_CB_MIN = 0.85         # a displacement hull this full is meshed as a box
UNITS = {
    "omega": "rad/s", "heading": "rad", "rho": "kg/m^3", "g": "m/s^2", "mass": "kg", "length": "m",
    "beam": "m", "draft": "m", "draft_mesh": "m", "displaced_volume": "m^3", "center_of_gravity": "m",
    "mesh_panel_size": "m",
    "inertia_matrix": "kg, kg m, kg m^2 (6-DOF rigid-body, about the reference point)",
    "hydrostatic_stiffness": "N/m, N, N m/rad", "viscous_damping": "N s/m, N m s/rad",
    "added_mass": "kg, kg m, kg m^2", "radiation_damping": "N s/m, N s, N m s/rad",
    "excitation_amplitude": "N/m, N m/m (per unit wave amplitude)", "excitation_phase": "rad",
    "froude_krylov_amplitude": "N/m, N m/m (per unit wave amplitude)", "froude_krylov_phase": "rad",
    "rao_amplitude": "m/m (surge, sway, heave), rad/m (roll, pitch, yaw)", "rao_phase": "rad",
    "drift": "N/m^2 (X, Y), N m/m^2 (N): per unit wave amplitude squared, body axes",
}


# ---- particulars ------------------------------------------------------------------------------

def particulars(path: str) -> dict:
    """The hull's numbers for the BEM model from its ship file (validated by ship_file)."""
    from tug_dynamics.ship_file import ship_config, validate_displacement
    src, cfg = ship_config(path)
    if cfg.get("model") != "displacement":
        raise ValueError(f"{src}: not a displacement hull (model: {cfg.get('model')!r})")
    ship = validate_displacement(src, cfg)
    h, rho = ship.hull, float(ship.water_density)
    L, B, T, m = float(h.length), float(h.beam), float(h.draft), float(h.mass)
    cb = m / (rho * L * B * T)
    box = cb >= BOX_CB_MIN
    roll = getattr(ship, "roll", None)
    notes = {}
    if roll is not None:
        z_g, kxx, zeta = float(roll.z_g), float(roll.radius_of_gyration), float(roll.damping_ratio)
        notes["z_g"] = f"{z_g:g} m: the file's roll.z_g"
        notes["roll_radius_of_gyration"] = f"{kxx:g} m: the file's roll.radius_of_gyration"
        notes["roll_damping_ratio"] = f"{zeta:g}: the file's roll.damping_ratio (of critical, added to potential damping)"
    else:
        z_g, kxx, zeta = 0.0, 0.35 * B, (0.10 if box else 0.05)
        notes["z_g"] = "0 m: G on the still waterline (KG = T), no roll section in the file"
        notes["roll_radius_of_gyration"] = f"{kxx:g} m: 0.35 B"
        notes["roll_damping_ratio"] = (f"{zeta:g} of critical, added to potential damping: "
                                       + ("square-bilged box" if box else "round-bilged ship form"))
    kyy = 0.25 * L
    notes["pitch_radius_of_gyration"] = f"{kyy:g} m: 0.25 L"
    notes["yaw_radius_of_gyration"] = f"{float(h.yaw_radius_of_gyration):g} m: the file's hull.yaw_radius_of_gyration"
    gm_target, pw = None, None
    if box:
        notes["geometry"] = (f"box {L:g} x {B:g} m, draft Cb T = {cb * T:.4g} m (file draft {T:g} m, Cb {cb:.3f}): "
                             "floats at the file's mass with the full waterplane")
    else:
        if roll is not None:
            pw = waterplane_exponent(float(roll.bm), m / rho, L, B)
            src_wp = f"the waterline's I_T gives the file's roll.bm {float(roll.bm):g} m"
        else:
            cwp = (1.0 + 2.0 * cb) / 3.0
            pw = cwp / (1.0 - cwp)
            src_wp = f"Cwp = (1 + 2 Cb)/3 = {cwp:.3f} (Schneekluth & Bertram 1998, U-sections)"
            gm_target = 1.0
            notes["z_g"] = "G placed for GM_T = 1.0 m (a loaded container ship's order; no roll section in the file)"
        notes["geometry"] = (f"y = B/2 (1 - |2x/L|^p(z))(1 - |z/T|^q), q = {CM_SHIP / (1 - CM_SHIP):g} (Cm {CM_SHIP}), "
                             f"p(z) = p_k + (p_w - p_k) (1 - |z|/T)^3, p_w = {pw:.4g}: {src_wp}; p_k solved for the "
                             f"displacement m / rho (Cb {cb:.3f}); hull shifted so its centre of buoyancy is at x_g")
    return dict(name=ship.name, src=src, L=L, B=B, T=T, m=m, rho=rho, cb=cb, box=box, pw=pw, gm_target=gm_target, x_g=float(h.x_g), z_g=z_g,
                kxx=kxx, kyy=kyy, kzz=float(h.yaw_radius_of_gyration), zeta=zeta, notes=notes)


# ---- meshes -----------------------------------------------------------------------------------

def box_mesh(L: float, B: float, T: float, h: float):
    """Closed-bottom box (no top), reflection-symmetric about xOz and yOz, panels about h."""
    import capytaine as cpt
    nx = max(4, 2 * math.ceil(L / h / 2))
    ny = max(2, 2 * math.ceil(B / h / 2))
    nz = max(1, math.ceil(T / h))
    return cpt.mesh_parallelepiped(size=(L, B, T), center=(0.0, 0.0, -T / 2), resolution=(nx, ny, nz),
                                   missing_sides={"top"}, reflection_symmetry=True)


def _ship_vertices(L, B, T, pw, pk, nx, nz):
    q = CM_SHIP / (1.0 - CM_SHIP)
    xs = -0.5 * L * np.cos(np.linspace(0.0, math.pi, nx + 1))      # clustered towards the ends
    zs = -T * np.linspace(0.0, 1.0, nz + 1) ** 0.75                 # clustered towards the keel
    X, Z = np.meshgrid(xs, zs, indexing="ij")
    zeta = np.abs(Z / T)
    p = pk + (pw - pk) * (1.0 - zeta) ** 3
    Y = np.maximum(0.5 * B * (1.0 - np.abs(2.0 * X / L) ** p) * (1.0 - zeta ** q), 0.0)
    return np.stack([X, Y, Z], axis=-1).reshape(-1, 3)


def _half_volume(verts, nx, nz):
    """Volume between the port half surface and the centreplane (divergence theorem, y only)."""
    P = verts.reshape(nx + 1, nz + 1, 3)
    a, b, c, d = P[:-1, :-1], P[:-1, 1:], P[1:, 1:], P[1:, :-1]
    n = 0.5 * np.cross(c - a, d - b)                                  # area vector of each quad
    yc = 0.25 * (a + b + c + d)[..., 1]
    return abs(float(np.sum(yc * n[..., 1])))


def waterplane_exponent(bm: float, volume: float, L: float, B: float) -> float:
    """p_w of the waterline y = B/2 (1 - |2x/L|^p_w) whose I_T = (2/3) int y^3 dx gives BM = I_T / V."""
    def bm_of(p):
        integral = 1.0 - 3.0 / (p + 1.0) + 3.0 / (2.0 * p + 1.0) - 1.0 / (3.0 * p + 1.0)
        return (2.0 / 3.0) * (0.5 * B) ** 3 * L * integral / volume
    lo, hi = 0.3, 60.0
    if not bm_of(lo) <= bm <= bm_of(hi):
        raise ValueError(f"BM {bm:g} m out of reach of the parametric waterline")
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if bm_of(mid) < bm else (lo, mid)
    return 0.5 * (lo + hi)


def ship_mesh(L: float, B: float, T: float, volume: float, pw: float, h: float, nz_min: int = 10):
    """The parametric hull (module docstring), port half meshed and mirrored about xOz; the keel
    exponent p_k solved (bisection) so the mesh displaces `volume`."""
    import capytaine as cpt
    nx = max(8, 2 * math.ceil(L / h / 2))
    nz = max(nz_min, math.ceil((T + 0.5 * B) / h))
    lo, hi = 0.05, pw
    if 2.0 * _half_volume(_ship_vertices(L, B, T, pw, lo, nx, nz), nx, nz) > volume:
        raise ValueError("displacement too small for the parametric hull")
    if 2.0 * _half_volume(_ship_vertices(L, B, T, pw, hi, nx, nz), nx, nz) < volume:
        raise ValueError("displacement too large for the parametric hull")
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        v = 2.0 * _half_volume(_ship_vertices(L, B, T, pw, mid, nx, nz), nx, nz)
        lo, hi = (mid, hi) if v < volume else (lo, mid)
    pk = 0.5 * (lo + hi)
    verts = _ship_vertices(L, B, T, pw, pk, nx, nz)
    idx = np.arange((nx + 1) * (nz + 1)).reshape(nx + 1, nz + 1)
    faces = []
    for i in range(nx):
        for j in range(nz):
            quad = [idx[i, j], idx[i, j + 1], idx[i + 1, j + 1], idx[i + 1, j]]
            pts = verts[quad]
            if np.linalg.norm(np.cross(pts[2] - pts[0], pts[3] - pts[1])) < 1e-9 * L * L:
                continue                                          # degenerate (zero area)
            faces.append(quad)
    faces = np.array(faces)
    half = cpt.Mesh(vertices=verts, faces=faces)
    if np.sum(half.faces_normals[:, 1] * half.faces_areas) < 0.0:  # normals out of the hull (+y, port half)
        half = cpt.Mesh(vertices=verts, faces=faces[:, ::-1])
    return cpt.ReflectionSymmetricMesh(half=half, plane="xOz"), pk


def panel_size(p: dict, coarse: bool) -> float:
    return p["L"] / (20.0 if coarse else 40.0)


def make_body(p: dict, coarse: bool):
    """(FloatingBody with the six rigid dofs about the origin, mesh panel count, panel size)."""
    import capytaine as cpt
    h = panel_size(p, coarse)
    if p["box"]:
        mesh = box_mesh(p["L"], p["B"], p["cb"] * p["T"], h)
    else:
        mesh, pk = ship_mesh(p["L"], p["B"], p["T"], p["m"] / p["rho"], p["pw"], h, 6 if coarse else 10)
        p["notes"]["geometry"] += f" (p_k = {pk:.4g})"
    if p["x_g"] != 0.0:
        mesh = mesh.translated((p["x_g"], 0.0, 0.0))                  # LCB at LCG: trimmed equilibrium
    if p.get("gm_target") is not None:                                # G for the target GM_T
        probe = cpt.FloatingBody(mesh=mesh, dofs=cpt.rigid_body_dofs(rotation_center=(0.0, 0.0, 0.0)),
                                 center_of_mass=(p["x_g"], 0.0, 0.0), mass=p["m"])
        c44 = float(cpt.compute_hydrostatics_dataset(probe, g=G, rho=p["rho"])["hydrostatic_stiffness"]
                    .sel(influenced_dof="Roll", radiating_dof="Roll"))
        p["z_g"] = (c44 - p["gm_target"] * p["m"] * G) / (p["m"] * G)
        p["notes"]["z_g"] += f": z_g = {p['z_g']:.4g} m"
    lid = mesh.generate_lid(z=0.0)
    body = cpt.FloatingBody(mesh=mesh, lid_mesh=lid, dofs=cpt.rigid_body_dofs(rotation_center=(0.0, 0.0, 0.0)),
                            center_of_mass=(p["x_g"], 0.0, p["z_g"]), mass=p["m"], name=p["name"])
    return body, mesh.nb_faces, h


def rigid_inertia(m: float, rg, kxx: float, kyy: float, kzz: float) -> np.ndarray:
    """6x6 rigid-body mass matrix about the origin for G at rg (Fossen 2021 ch. 3)."""
    rg = np.asarray(rg, float)
    S = np.array([[0.0, -rg[2], rg[1]], [rg[2], 0.0, -rg[0]], [-rg[1], rg[0], 0.0]])
    Ig = m * np.diag([kxx ** 2, kyy ** 2, kzz ** 2])
    M = np.zeros((6, 6))
    M[:3, :3] = m * np.eye(3)
    M[:3, 3:] = -m * S
    M[3:, :3] = m * S
    M[3:, 3:] = Ig - m * S @ S
    return M


# ---- the BEM run --------------------------------------------------------------------------------

def grids(L: float, coarse: bool):
    w_hi = max(2.5, 2.5 * math.sqrt(45.0 / L))
    omega = np.linspace(0.2, w_hi, 12 if coarse else 30)
    step = 30.0 if coarse else 15.0
    half = np.radians(np.arange(0.0, 180.0 + 0.5 * step, step))
    return omega, half


def solve(p: dict, coarse: bool = False, omega=None, half_headings=None, drift: bool = True, progress=False):
    """Everything for one hull; returns the mapping written to the .npz (headings 0..360)."""
    import capytaine as cpt
    import xarray as xr
    from capytaine.post_pro import far_field_mean_drift_force
    cpt.set_logging("ERROR")
    w0, b0 = grids(p["L"], coarse)
    omega = w0 if omega is None else np.asarray(omega, float)
    half = b0 if half_headings is None else np.asarray(half_headings, float)
    body, nfaces, h = make_body(p, coarse)
    rho = p["rho"]
    coords = dict(omega=omega, wave_direction=half, radiating_dof=list(CPT_DOFS), water_depth=[np.inf],
                  rho=[rho], g=[G])
    if drift:
        dth = math.radians(5.0)                 # Kochin angles: 0..2 pi and a margin either side
        coords["theta"] = np.arange(-2, 75) * dth
    ds = cpt.BEMSolver(method="indirect").fill_dataset(xr.Dataset(coords=coords), body, progress_bar=progress,
                                                     _check_wavelength=False)
    hs = cpt.compute_hydrostatics_dataset(body, g=G, rho=rho)
    order = dict(influenced_dof=list(CPT_DOFS), radiating_dof=list(CPT_DOFS))
    A = ds["added_mass"].sel(**order).transpose("omega", "influenced_dof", "radiating_dof").values
    Bp = ds["radiation_damping"].sel(**order).transpose("omega", "influenced_dof", "radiating_dof").values
    F = ds["excitation_force"].sel(influenced_dof=list(CPT_DOFS)).transpose("omega", "wave_direction", "influenced_dof").values
    FK = ds["Froude_Krylov_force"].sel(influenced_dof=list(CPT_DOFS)).transpose("omega", "wave_direction", "influenced_dof").values
    C = hs["hydrostatic_stiffness"].sel(**order).values
    M = rigid_inertia(p["m"], (p["x_g"], 0.0, p["z_g"]), p["kxx"], p["kyy"], p["kzz"])

    # viscous roll damping: zeta of critical at the undamped roll natural frequency
    i44 = M[3, 3]
    wn = math.sqrt(max(C[3, 3], 0.0) / (i44 + A[0, 3, 3]))
    for _ in range(20):
        wn = math.sqrt(max(C[3, 3], 0.0) / (i44 + np.interp(wn, omega, A[:, 3, 3])))
    Bv = np.zeros((6, 6))
    Bv[3, 3] = 2.0 * p["zeta"] * math.sqrt(max(C[3, 3], 0.0) * (i44 + np.interp(wn, omega, A[:, 3, 3])))

    # RAOs: [-w^2 (M + A) - i w (B + Bv) + C] X = F   (e^{-i w t})
    H = (-omega[:, None, None] ** 2 * (M + A) - 1j * omega[:, None, None] * (Bp + Bv) + C)
    X = np.linalg.solve(H[:, None, :, :], F[..., None])[..., 0]          # (nw, nb_half, 6)

    D = np.zeros(X.shape[:2] + (3,))
    if drift:
        Xda = xr.DataArray(X, dims=("omega", "wave_direction", "radiating_dof"),
                           coords=dict(omega=omega, wave_direction=half, radiating_dof=list(CPT_DOFS)))
        dd = ds.squeeze()
        dd = dd.assign(kochin_radiation=dd["kochin_radiation"].sel(radiating_dof=list(CPT_DOFS)))
        fd = far_field_mean_drift_force(Xda, dd)
        for j, name in enumerate(("drift_force_surge", "drift_force_sway", "drift_force_yaw")):
            v = fd[name].transpose("omega", "wave_direction_k", "wave_direction_l").values
            D[..., j] = np.real(np.diagonal(v, axis1=1, axis2=2))

    # mirror to 180..360 deg (port/starboard symmetric hull)
    full = np.radians(np.arange(0.0, 360.0 - 1e-9, math.degrees(half[1] - half[0]))) if len(half) > 1 else half
    sign6 = np.array([1, -1, 1, -1, 1, -1], float)
    sign3 = np.array([1, -1, -1], float)

    def mirror(a, sign):
        out = np.empty(a.shape[:1] + (len(full),) + a.shape[2:], a.dtype)
        for ib, b in enumerate(full):
            bm = b if b <= math.pi + 1e-9 else 2.0 * math.pi - b
            j = int(np.argmin(np.abs(half - bm)))
            out[:, ib] = a[:, j] if b <= math.pi + 1e-9 else a[:, j] * sign
        return out

    Xf, Ff, FKf, Df = mirror(X, sign6), mirror(F, sign6), mirror(FK, sign6), mirror(D, sign3)
    notes = dict(p["notes"])
    notes.update(roll_natural_frequency=f"{wn:.4g} rad/s (undamped, A44 at w_n)",
                 viscous_roll_damping=f"{Bv[3, 3]:.6g} N m s/rad",
                 reference_point="(0, 0, 0): midships, centreline, still waterline; body axes x fwd, y port, z up",
                 heading_convention="beta: direction the waves travel towards, CCW from body +x; 180 deg head seas",
                 phase_convention="response = a |RAO| cos(theta + phase), theta = k (x cos beta + y sin beta) - w t + phi at the reference point",
                 drift="Maruo (1960) far-field, capytaine.post_pro.far_field_mean_drift_force, diagonal terms",
                 solver=f"capytaine {cpt.__version__}, Delhommeau Green function, indirect method, lid on the waterplane, deep water, zero speed")
    return dict(
        format_version=np.int64(FORMAT_VERSION), ship=np.str_(p["name"]), units=np.str_(json.dumps(UNITS)),
        notes=np.str_(json.dumps(notes)), mesh_faces=np.int64(nfaces), mesh_panel_size=np.float64(h),
        rho=np.float64(rho), g=np.float64(G), mass=np.float64(p["m"]), length=np.float64(p["L"]),
        beam=np.float64(p["B"]), draft=np.float64(p["T"]),
        draft_mesh=np.float64(p["cb"] * p["T"] if p["box"] else p["T"]),
        displaced_volume=np.float64(float(hs["disp_mass"]) / rho),
        center_of_gravity=np.array([p["x_g"], 0.0, p["z_g"]]),
        omega=omega, heading=full, dofs=np.array(DOFS),
        inertia_matrix=M, hydrostatic_stiffness=C, viscous_damping=Bv, added_mass=A, radiation_damping=Bp,
        excitation_amplitude=np.abs(Ff), excitation_phase=np.angle(Ff),
        froude_krylov_amplitude=np.abs(FKf), froude_krylov_phase=np.angle(FKf),
        rao_amplitude=np.abs(Xf), rao_phase=np.angle(Xf), drift=Df)


def displacement_ships() -> list:
    import glob
    import yaml
    out = []
    for f in sorted(glob.glob(os.path.join(SHIPS, "*.yaml"))):
        with open(f) as fh:
            if (yaml.safe_load(fh) or {}).get("model") == "displacement":
                out.append(os.path.splitext(os.path.basename(f))[0])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ship", action="append", help="ship file name (repeatable); default: every displacement hull")
    ap.add_argument("--coarse", action="store_true", help="coarse mesh and grids")
    ap.add_argument("--out", default=os.path.join(SHIPS, "hydro"), help="output directory")
    ap.add_argument("--progress", action="store_true", help="Capytaine's progress bar")
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    names = a.ship or displacement_ships()
    t_all = time.time()
    for name in names:
        t0 = time.time()
        path = name if name.endswith(".yaml") else os.path.join(SHIPS, name + ".yaml")
        p = particulars(path)
        data = solve(p, coarse=a.coarse, progress=a.progress)
        out = os.path.join(a.out, p["name"] + ".npz")
        np.savez_compressed(out, **data)
        i_h = int(np.argmin(np.abs(data["heading"] - math.pi / 2)))
        print(f"{p['name']}: {int(data['mesh_faces'])} panels, {len(data['omega'])} x {len(data['heading'])} "
              f"(w, beta), heave RAO at w_min {data['rao_amplitude'][0, i_h, 2]:.3f}, "
              f"{time.time() - t0:.1f} s -> {os.path.relpath(out, ROOT)}", flush=True)
    print(f"all: {time.time() - t_all:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
