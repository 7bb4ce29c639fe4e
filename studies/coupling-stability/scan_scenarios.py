"""The proposed bound over the library's scenarios: omega_max h <= 0.2 with
omega_max^2 = (EA / L) (1/m_a + 1/m_b), L the deployed (unstretched) length at the start, m the
surge mass incl. added mass of the vessel at each end (inf: fixed end or prescribed motion;
a free end does not couple). Lists f_min = omega_max / 0.2 (Hz) against the scenario's rate."""
import copy
import glob
import math
import os

import numpy as np
import yaml

from rope_model.models import load_params
from tug_dynamics.ship_file import load_ship
from tug_dynamics.vessel import ExternalWrench, VesselState

SC = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src") + "/" + "scenario_runner/scenarios/"
SHIPS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src") + "/" + "tug_dynamics/ships/"
ROPES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src") + "/" + "rope_model/ropes/"
_mass = {}


def surge_mass(ship_file):
    if ship_file not in _mass:
        v = load_ship(SHIPS + ship_file)
        v.set_state(VesselState.at_rest())
        w, w2 = copy.deepcopy(v), copy.deepcopy(v)
        w.step(1e-3, [])
        w2.step(1e-3, [ExternalWrench(np.array([1e5, 0, 0.0]), np.zeros(3))])
        _mass[ship_file] = 1e5 / ((w2.state.linear_velocity_body[0] - w.state.linear_velocity_body[0]) / 1e-3)
    return _mass[ship_file]


_lam = {}


def max_mobility(ship_file, att):
    """Largest eigenvalue of the attachment's horizontal mobility (1 / smallest effective mass)."""
    if (ship_file, att) not in _lam:
        from point_mobility import mobility
        G = mobility(ship_file, att)
        _lam[(ship_file, att)] = float(np.linalg.eigvalsh(0.5 * (G + G.T)).max())
    return _lam[(ship_file, att)]


def end_mobility(spec, vessels):
    if spec in ("fixed", "free"):
        return 0.0
    name, att = spec.split("/")
    v = vessels[name]
    return 0.0 if v.get("motion") else max_mobility(v["ship_file"], att)


def end_mass(spec, vessels):
    if spec in ("fixed",):
        return math.inf
    if spec == "free":
        return None
    name = spec.split("/")[0]
    v = vessels[name]
    if v.get("motion"):
        return math.inf
    return surge_mass(v["ship_file"])


rows = []
for path in sorted(glob.glob(SC + "*.yaml")):
    sc = yaml.safe_load(open(path))
    if not sc.get("ropes"):
        continue
    vessels = {v["name"]: v for v in sc.get("vessels", [])}
    rate = float(sc.get("exchange_rate", 50.0))
    for r in sc["ropes"]:
        p = load_params(ROPES + r["rope_file"])
        ea = float(getattr(p, "ea", None) or getattr(p, "axial_stiffness", None) or p.EA)
        L = float(r.get("deployed_length") or p.length)
        ma, mb = end_mass(r["end_a"], vessels), end_mass(r["end_b"], vessels)
        if ma is None or mb is None or (math.isinf(ma) and math.isinf(mb)):
            note = "one end free or both fixed: no vessel-rope spring"
            rows.append((os.path.basename(path), r["name"], r["rope_file"], L, ea / L, math.nan, rate, math.nan, note,
                         math.nan))
            continue
        inv = (0 if math.isinf(ma) else 1 / ma) + (0 if math.isinf(mb) else 1 / mb)
        w = math.sqrt(ea / L * inv)
        wc = math.sqrt(ea / L * (end_mobility(r["end_a"], vessels) + end_mobility(r["end_b"], vessels)))
        rows.append((os.path.basename(path), r["name"], r["rope_file"], L, ea / L, w, rate, w / rate, "", wc))

print(f"{'scenario':36s} {'rope':13s} {'file':20s} {'L m':>6s} {'EA/L N/m':>9s} {'w rad/s':>8s} {'rate':>5s} "
      f"{'w h':>6s} {'f_min(0.2)':>10s} {'w_cons':>7s} {'wc h':>6s}  verdict (on wc h)")
for sc, name, f, L, k, w, rate, wh, note, wc in rows:
    whc = wc / rate
    verdict = note or ("ok" if whc <= 0.2 else ("WARN (0.2 < w h <= 0.5)" if whc <= 0.5 else "REFUSE (w h > 0.5)"))
    print(f"{sc:36s} {name:13s} {f:20s} {L:6.0f} {k:9.3g} {w:8.3f} {rate:5g} {wh:6.3f} {w / 0.2 if w == w else math.nan:10.1f} {wc:7.3f} {wc / rate:6.3f}  {verdict}")
