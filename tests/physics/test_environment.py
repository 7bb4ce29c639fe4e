"""The environment on a vessel (issue 18): Blendermann wind loads, free drift in a beam wind, a
vessel in a current, squat, grounding, the bathymetry grid and the environment's bad input.
No ROS; each truth is computed by hand here, independently of the code under test."""
import math

import numpy as np
import pytest

from sea_environment.bathymetry import BathymetryError, DepthGrid
from sea_environment.environment import Environment
from sea_environment.shallow_water import squat
from sea_environment.wind import KNOT, apparent_wind
from sea_environment.wind_loads import BLENDERMANN_TABLE, Windage, blendermann_coefficients, wind_wrench_body
from tug_dynamics.environment_loads import GROUND_FRICTION, VesselInEnvironment
from tug_dynamics.ship_file import ShipFileError, load_ship
from tug_dynamics.vessel import Command, VesselState

RHO_AIR = 1.225


# ---- Blendermann (1994) ---------------------------------------------------------------------
# His Table 2 as printed (CD_t, CD_l,AF bow, CD_l,AF stern, delta, kappa) for three types, typed
# here from the paper, not from the module.
PUBLISHED = {"container_ship_loaded": (0.90, 0.55, 0.55, 0.40, 1.4),
             "tanker_loaded": (0.70, 0.90, 0.55, 0.40, 3.1),
             "offshore_supply_vessel": (0.90, 0.55, 0.80, 0.55, 1.2)}


@pytest.mark.parametrize("ship_type", sorted(PUBLISHED))
def test_blendermann_table_matches_the_paper(ship_type):
    assert BLENDERMANN_TABLE[ship_type] == pytest.approx(PUBLISHED[ship_type], abs=1e-12)


@pytest.mark.parametrize("deg", [0.0, 30.0, 60.0, 90.0, 120.0, 150.0, 180.0])
def test_blendermann_curves_at_tabulated_angles(deg):
    """C_X, C_Y, C_K, C_N of a container ship against Blendermann's formulas worked by hand."""
    w = Windage("container_ship_loaded", frontal_area=420.0, lateral_area=2250.0, centroid_x=-4.0,
                centroid_height=7.0, length_overall=183.0)
    cdt, bow, stern, delta, kappa = PUBLISHED["container_ship_loaded"]
    g = math.radians(deg)
    cdlaf = bow if deg <= 90.0 else stern
    cdl = cdlaf * 420.0 / 2250.0
    den = 1.0 - 0.5 * delta * (1.0 - cdl / cdt) * math.sin(2.0 * g) ** 2
    cy = cdt * math.sin(g) / den
    expect = (-cdlaf * math.cos(g) / den, cy, kappa * 7.0 / (2250.0 / 183.0) * cy,
              (-4.0 / 183.0 - 0.18 * (g - math.pi / 2.0)) * cy)
    assert blendermann_coefficients(g, w) == pytest.approx(expect, abs=1e-12)
    # the published limits: head wind C_X = -CD_l,AF(bow), beam wind C_Y = CD_t, stern wind +CD_l,AF(stern)
    if deg == 0.0:
        assert blendermann_coefficients(g, w)[0] == pytest.approx(-bow)
    if deg == 90.0:
        assert blendermann_coefficients(g, w)[1] == pytest.approx(cdt)
    if deg == 180.0:
        assert blendermann_coefficients(g, w)[0] == pytest.approx(stern)


def test_wind_from_port_pushes_to_starboard_and_turns_the_bow_downwind():
    """REP-103 signs: a port beam wind gives -Y; a centroid forward of midship makes the bow fall
    off to starboard (N < 0); mirrored for a starboard wind."""
    w = Windage("offshore_supply_vessel", 42.0, 105.0, 2.0, 2.8, 26.0)
    fx, fy, xp, zp, n = wind_wrench_body(20.0, math.pi / 2, w)
    q = 0.5 * RHO_AIR * 400.0
    assert fx == pytest.approx(0.0, abs=1e-9)
    assert fy == pytest.approx(-q * 105.0 * 0.90, rel=1e-12)
    assert xp == pytest.approx(2.0) and n < 0.0 and zp == pytest.approx(1.2 * 2.8)
    fx2, fy2, xp2, zp2, n2 = wind_wrench_body(20.0, -math.pi / 2, w)
    assert (fy2, n2) == pytest.approx((-fy, -n))


def test_beam_wind_free_drift_reaches_the_hand_calculated_speed():
    """Box barge free in a steady 20 m/s beam wind: the drift speed v where
    1/2 rho_a (V - v)^2 A_L CD_t = 1/2 rho L T |Y'vv| v^2 (Y'vv the file's cross-flow term; at
    u = r = 0 the hull's other sway terms vanish), i.e. v = k V / (1 + k),
    k = sqrt(rho_a A_L CD_t / (rho L T |Y'vv|))."""
    barge = load_ship("box_barge_000.yaml")
    env = Environment.from_mapping({"wind": {"speed_kn": 20.0 / KNOT, "from_deg": 0.0, "gusts": False}})
    coupling = VesselInEnvironment(barge, env)
    dt = 0.05
    for i in range(8000):            # 400 s: the drift's time constant is about 30 s
        barge.step(dt)
    k = math.sqrt(RHO_AIR * 25.0 * 0.70 / (1025.0 * 50.0 * 0.5 * 1.0))
    v_hand = k * 20.0 / (1.0 + k)
    vel = barge.state.linear_velocity_body
    # a north wind drives the barge (heading east) south: to starboard, -y body
    assert -vel[1] == pytest.approx(v_hand, rel=1e-3)
    assert abs(vel[0]) < 1e-6 and abs(barge.state.rpy[2]) < 1e-6
    assert coupling.status.apparent_wind_speed == pytest.approx(20.0 - v_hand, rel=1e-3)
    assert coupling.status.apparent_wind_angle == pytest.approx(math.pi / 2, abs=1e-9)


@pytest.mark.parametrize("ship", ["harbour_tug.yaml", "box_barge_000.yaml", "s175_003.yaml",
                                  "barge_002_full.yaml", "planing_40ft.yaml"])
def test_unpowered_vessel_drifting_with_the_current_stays_with_it(ship):
    """Galilean invariance: a vessel whose velocity over ground is the current's has no velocity
    through the water, so no hydrodynamic force; it keeps drifting with the stream, heading kept."""
    vessel = load_ship(ship)
    env = Environment.from_mapping({"current": {"speed_kn": 2.0, "towards_deg": 45.0}})
    coupling = VesselInEnvironment(vessel, env)
    c = 2.0 * KNOT * np.array([math.sin(math.radians(45.0)), math.cos(math.radians(45.0))])
    yaw = 0.3
    body = np.array([math.cos(yaw) * c[0] + math.sin(yaw) * c[1], -math.sin(yaw) * c[0] + math.cos(yaw) * c[1], 0.0])
    state = vessel.state
    vessel.set_state(VesselState(np.array([0.0, 0.0, state.position[2]]), np.array([0.0, state.rpy[1], yaw]),
                                 body, np.zeros(3)))
    dt = 0.05
    for i in range(2000):
        vessel.step(dt)
    s = vessel.state
    assert s.rpy[2] == pytest.approx(yaw, abs=1e-3)
    cy, sy = math.cos(s.rpy[2]), math.sin(s.rpy[2])
    v = s.linear_velocity_body
    assert [cy * v[0] - sy * v[1], sy * v[0] + cy * v[1]] == pytest.approx(c, abs=2e-3 * 2.0 * KNOT)
    assert s.position[:2] == pytest.approx(c * 100.0, abs=0.5)


def test_vessel_released_in_a_current_is_taken_up_by_it():
    """From rest in a 2 kn stream the box barge's speed through the water decays (the hull's drag
    is quadratic: like 1/t) below 5 % of the stream within 20 minutes."""
    barge = load_ship("box_barge_000.yaml")
    env = Environment.from_mapping({"current": {"speed_kn": 2.0, "towards_deg": 45.0}})
    coupling = VesselInEnvironment(barge, env)
    dt, through = 0.1, []
    for i in range(12000):
        barge.step(dt)
        through.append(barge.status().speed_through_water)
    assert through[0] > 0.9 * 2.0 * KNOT
    assert through[-1] < 0.05 * 2.0 * KNOT


def test_tidal_stream_reverses_and_shear_grows_across_it():
    env = Environment.from_mapping({"current": {"speed_kn": 2.0, "towards_deg": 90.0, "shear_per_s": 0.001,
                                                "tidal_period_s": 1000.0}})
    u = 2.0 * KNOT
    assert env.current_velocity(0.0, 0.0, 0.0) == pytest.approx([u, 0.0], abs=1e-12)
    assert env.current_velocity(500.0, 0.0, 0.0) == pytest.approx([-u, 0.0], abs=1e-12)   # half a period: ebb
    assert env.current_velocity(250.0, 0.0, 0.0) == pytest.approx([0.0, 0.0], abs=1e-12)  # slack water
    # a stream setting east: its left is north; 100 m north the stream is 0.1 m/s faster
    assert env.current_velocity(0.0, 0.0, 100.0) == pytest.approx([u + 0.1, 0.0], abs=1e-12)
    v = env.current_velocity(0.0, np.zeros(3), np.array([-100.0, 0.0, 100.0]))
    assert v[:, 0] == pytest.approx([u - 0.1, u, u + 0.1], abs=1e-12)


# ---- depth -------------------------------------------------------------------------------
def _grid_file(tmp_path, rows, header=None, name="depth.asc"):
    head = header if header is not None else ["ncols 4", "nrows 3", "xllcorner -100.0", "yllcorner -50.0",
                                               "cellsize 50.0", "NODATA_value -9999"]
    path = tmp_path / name
    path.write_text("\n".join(head + [" ".join(str(v) for v in r) for r in rows]) + "\n")
    return str(path)


def wavy_grid_file(tmp_path, nx, ny, corner, cell, mean, amplitude, ki, kj):
    """An ESRI grid of depths mean + amplitude sin(ki i + kj j) (row i, column j), its lower-left
    corner at `corner` (the samplers' tests: a seabed that varies in both directions)."""
    rows = [[f"{mean + amplitude * math.sin(ki * i + kj * j):.3f}" for j in range(nx)] for i in range(ny)]
    return _grid_file(tmp_path, rows, [f"ncols {nx}", f"nrows {ny}", f"xllcorner {corner[0]}",
                                       f"yllcorner {corner[1]}", f"cellsize {cell}"])


def test_bathymetry_grid_reproduces_a_plane(tmp_path):
    """Bilinear interpolation is exact for a plane: depth = 10 + 0.02 x - 0.01 y sampled at the
    cell centres (x = -75, -25, 25, 75; y = 75 (first row, north), 25, -25)."""
    def plane(x, y):
        return 10.0 + 0.02 * x - 0.01 * y
    xs, ys = [-75.0, -25.0, 25.0, 75.0], [75.0, 25.0, -25.0]
    path = _grid_file(tmp_path, [[plane(x, y) for x in xs] for y in ys])
    grid = DepthGrid.load(path)
    for x, y in [(0.0, 0.0), (-60.0, 70.0), (33.3, -20.0), (74.0, 24.0)]:
        depth = grid.depth_at(x, y)
        assert isinstance(depth, float) and depth == pytest.approx(plane(x, y), abs=1e-9)
    # outside the grid: the nearest edge value
    assert grid.depth_at(500.0, 0.0) == pytest.approx(plane(75.0, 0.0), abs=1e-9)
    env = Environment.from_mapping({"depth": {"grid": "depth.asc"}}, base_dir=str(tmp_path))
    assert env.depth_at(np.array([0.0, 10.0]), np.array([0.0, 0.0])) == pytest.approx([10.0, 10.2], abs=1e-9)


def test_scalar_depth_lookup_equals_scipys_interpolation(tmp_path):
    """The vessel's per-step lookup (hand-written bilinear) against scipy's RegularGridInterpolator
    on a rough grid, at random points inside and outside it."""
    rng = np.random.default_rng(5)
    rows = rng.uniform(2.0, 40.0, size=(7, 9)).round(2).tolist()
    header = ["ncols 9", "nrows 7", "xllcenter 100.0", "yllcenter -300.0", "cellsize 25.0"]
    grid = DepthGrid.load(_grid_file(tmp_path, rows, header))
    pts = rng.uniform([50.0, -350.0], [350.0, -100.0], size=(200, 2))
    vector = grid.depth_at(pts[:, 0], pts[:, 1])
    scalar = [grid.depth_at(float(x), float(y)) for x, y in pts]
    assert scalar == pytest.approx(vector, abs=1e-9)


@pytest.mark.parametrize("rows,header,expect", [
    ([[1, 2, 3, 4], [1, 2, -3, 4], [1, 2, 3, 4]], None, "line 8, column 3: depth -3 m is negative"),
    ([[1, 2, 3, 4], [1, 2, "x", 4], [1, 2, 3, 4]], None, "line 8, column 3: 'x' is not a number"),
    ([[1, 2, 3, 4], [1, 2, 3], [1, 2, 3, 4]], None, "line 8: 3 values, the header says ncols 4"),
    ([[1, 2, 3, 4]], None, "1 rows of depths, the header says nrows 3"),
    ([[1, 2, 3, 4]] * 3, ["ncols 4", "nrows 3", "xllcorner 0", "cellsize 5"], "header key 'yllcorner' is missing"),
    # issue 30 item 6: a traceback (OverflowError, MemoryError), or accepted silently
    ([[1, 2, 3, 4]] * 3, ["ncols inf", "nrows 3", "xllcorner 0", "yllcorner 0", "cellsize 5"],
     "line 1: ncols inf is not a finite number"),
    ([[1, 2, 3, 4]] * 3, ["ncols 1000000000000", "nrows 3", "xllcorner 0", "yllcorner 0", "cellsize 5"],
     "line 6: 4 values, the header says ncols 1000000000000"),
    ([[1, 2, 3, 4]] * 3, ["ncols 4", "nrows 3", "nrows 3", "xllcorner 0", "yllcorner 0", "cellsize 5"],
     "line 3: header key 'nrows' given again (first on line 2)"),
    ([[1, 2, 3, 4]] * 3, ["ncols 4", "nrows 3", "xllcorner 0", "yllcorner 0", "xllcenter 2.5", "cellsize 5"],
     "the lower-left is given both as corner (xllcorner, yllcorner) and as centre (xllcenter)"),
    ([[1, 2, 3, 4]] * 3, ["ncols 4", "nrows 3", "xllcorner 0", "yllcorner 0", "cellsize 5", "rotation 5"],
     "line 6: unknown header key 'rotation'"),
])
def test_bad_bathymetry_file_names_file_and_entry(tmp_path, rows, header, expect):
    path = _grid_file(tmp_path, rows, header)
    with pytest.raises(BathymetryError) as err:
        DepthGrid.load(path)
    assert path in str(err.value) and expect in str(err.value)


def test_missing_bathymetry_file(tmp_path):
    with pytest.raises(BathymetryError, match="depth grid file not found"):
        Environment.from_mapping({"depth": {"grid": "nowhere.asc"}}, base_dir=str(tmp_path))


@pytest.mark.parametrize("bad,key", [({"depth": -2.0}, "depth"), ({"depth": 0.0}, "depth"),
                                     ({"wind": {"speed_kn": -1.0, "from_deg": 0.0}}, "wind.speed_kn"),
                                     ({"wind": {"speed_kn": 10.0}}, "wind.from_deg"),
                                     ({"current": {"speed_kn": 1.0}}, "current.towards_deg"),
                                     ({"current": [0.1, float("nan")]}, "current"),
                                     ({"wnd": {}}, "wnd")])
def test_bad_environment_names_the_key(bad, key):
    with pytest.raises(ValueError) as err:
        Environment.from_mapping(bad, "scenario.yaml environment")
    assert f"scenario.yaml environment: key '{key}'" in str(err.value)


def test_icorels_squat_by_hand():
    """S-175 (V = 21 120 m^3, L = 175 m) at 10 kn in 12 m of water: Fnh = 5.144 / sqrt(g 12)."""
    u, h = 10.0 * KNOT, 12.0
    fnh = u / math.sqrt(9.80665 * h)
    expect = 2.4 * 21120.4 / 175.0 ** 2 * fnh ** 2 / math.sqrt(1.0 - fnh ** 2)
    assert squat(u, h, 175.0, 21120.4) == pytest.approx(expect, rel=1e-4)
    assert squat(u, math.inf, 175.0, 21120.4) == 0.0


def test_running_aground_stops_the_vessel_within_the_friction_distance(tmp_path):
    """The tug steams at 4 m/s towards a shoal (depth 10 m falling to 1 m over 100 m). Aground
    (under-keel clearance < 0) the bottom's friction mu N at least mu rho g A_wp (T - h) decelerates
    it: it stops, and its kinetic energy bounds how far it slides: it never reaches the dry line."""
    tug = load_ship("harbour_tug.yaml", initial_state=VesselState(
        np.zeros(3), np.zeros(3), np.array([4.0, 0.0, 0.0]), np.zeros(3)))
    tug.set_command(Command(0.0, 0.0))

    # a shoal rising along x: 10 m up to x = 100, 1 m from x = 200, linear between (a grid whose
    # bilinear interpolation is exactly that ramp)
    grid = tmp_path / "shoal.asc"
    grid.write_text("ncols 4\nnrows 2\nxllcenter 0\nyllcenter -100\ncellsize 100\n"
                    "10 10 1 1\n10 10 1 1\n")
    env = Environment.from_mapping({"depth": {"grid": str(grid)}})
    coupling = VesselInEnvironment(tug, env)
    dt, grounded_at = 0.05, None
    for i in range(4000):
        tug.step(dt)
        if coupling.status.grounded and grounded_at is None:
            grounded_at = tug.state.position[0]
    assert grounded_at is not None
    # aground first where 10 - 9 (x - 100)/100 < T + squat, T = 3 m: x > 177.8 m less the squat,
    # at most ICORELS' at the starting 4 m/s in water as shallow as the draft
    from sea_environment.shallow_water import squat
    most_squat = squat(4.0, tug.draft, tug.length, tug.volume)
    assert most_squat > 0.0          # 0.82 m: x > 168.6 m
    assert grounded_at > 100.0 + 100.0 * (10.0 - tug.draft - most_squat) / 9.0
    assert abs(tug.state.linear_velocity_body[0]) < 0.05
    assert coupling.status.grounded and tug.state.position[0] < 200.0
    assert GROUND_FRICTION > 0.0


def test_wind_needs_the_ship_files_windage(tmp_path):
    env = Environment.from_mapping({"wind": {"speed_kn": 10.0, "from_deg": 0.0}})
    model = load_ship("barge_002_model.yaml")
    with pytest.raises(ValueError, match="no 'windage' section"):
        VesselInEnvironment(model, env)


def test_bad_windage_section_names_the_key():
    with pytest.raises(ShipFileError, match="windage.centroid_x"):
        load_ship("harbour_tug.yaml", overrides={"windage": {"centroid_x": 40.0}})
    with pytest.raises(ShipFileError, match="windage"):
        load_ship("harbour_tug.yaml", overrides={"windage": {"type": "battleship"}})


# ---- the anchor's chain against the depth -----------------------------------------------------
def test_anchor_holding_limit_is_the_catenary_touching_down_at_the_anchor():
    """At the limit H_max the catenary of a chain_out long chain from the hawse pipe (height h
    above the bottom) has its lowest point exactly at the anchor: with a = H / w, the point at
    height h lies at x = a acosh(1 + h/a) and the arc from the lowest point is a sinh(x/a)."""
    from tug_dynamics.maneuvering import anchor_holding_factor
    w, s, holding = 765.0, 137.5, 1e9          # a holding force never reached: the factor is H_max / it
    for h in (10.0, 30.0, 69.0, 120.0):
        h_max = anchor_holding_factor(holding, s, w, h) * holding
        a = h_max / w
        x = a * math.acosh(1.0 + h / a)
        assert a * math.sinh(x / a) == pytest.approx(s, rel=1e-9)
    assert anchor_holding_factor(holding, s, w, 140.0) == 0.0     # the chain does not reach the bottom
    assert anchor_holding_factor(1.0, s, w, 10.0) == 1.0          # a short, steep chain still lifts 1 N


@pytest.mark.parametrize("depth", [15.0, 60.0, 100.0, 150.0])
def test_s175_anchor_dredges_with_what_its_chain_allows(depth):
    """S-175 let go its anchor at 6 kn on 5 shackles (137.5 m) of 64 mm chain (765 N/m in
    water), hawse 9 m up: the dredging resistance (status anchor_force) is the paper's
    lambda_a W_a = 1.5 x 70608 N while the catenary can hold it, w (s^2 - h^2) / (2 h) beyond."""
    chain = {"anchor": {"chain_out": 137.5, "chain_weight": 765.0, "hawse_height": 9.0}}
    ship = load_ship("s175_003.yaml", overrides=chain, initial_state=VesselState(
        np.zeros(3), np.zeros(3), np.array([6.0 * KNOT, 0.0, 0.0]), np.zeros(3)))
    env = Environment.from_mapping({"depth": depth})
    coupling = VesselInEnvironment(ship, env)
    from tug_dynamics.vessel import ANCHOR_LET_GO
    ship.set_command(Command(0.0, 0.0, ANCHOR_LET_GO))
    for i in range(400):                 # 20 s: let go (15 s) and dredging
        ship.step(0.05)
    h = depth + 9.0
    lam_w = 1.5 * 70608.0
    expect = 0.0 if h >= 137.5 else min(lam_w, 765.0 * (137.5 ** 2 - h ** 2) / (2.0 * h))
    assert ship.status().anchor_force == pytest.approx(expect, rel=1e-6, abs=1e-6)


# ---- shallow water: Ankudinov's factors on the manoeuvring model --------------------------------
def _ankudinov_by_hand(L, B, T, cb, h):
    """The MARAD factors typed from their restatement (Taimuri et al. 2020; DMI's Y'v form)."""
    F = h / T - 1.0
    K0 = 1 + 0.0775 / F ** 2 - 0.011 / F ** 3 + 0.000068 / F ** 5
    K1 = -0.0643 / F + 0.0724 / F ** 2 - 0.0113 / F ** 3 + 0.0000767 / F ** 5
    K2 = 0.0342 / F
    b = cb * B * (1 + B / L) ** 2 / T
    fnv = K0 + K1 * b + K2 * b ** 2
    fnr = K0 + K1 * b / 2 + K2 * b ** 2 / 3
    fyr = K0 + 2 * K1 * b / 5 + 24 * K2 * b ** 2 / 105
    return 1.5 * fnv - 0.5, fyr, fnv, fnr


def test_ankudinov_factors_by_hand_and_their_deep_water_limit():
    from sea_environment.shallow_water import ankudinov_factors
    L, B, T, cb = 175.0, 25.4, 8.5, 0.559
    for ratio in (1.2, 1.5, 2.0, 3.0, 4.0, 6.0):
        got = ankudinov_factors(L, B, T, cb, ratio * T)[:4]
        assert got == pytest.approx(_ankudinov_by_hand(L, B, T, cb, ratio * T), rel=1e-12)
        if ratio >= 4.0:
            assert max(abs(f - 1.0) for f in got) < 0.05
    # the values the research notes list for the S-175 at h/T = 1.5 (f_nv, f_nr, f_yr)
    assert ankudinov_factors(L, B, T, cb, 1.5 * T)[1:4] == pytest.approx((1.363, 1.712, 1.414), abs=1e-3)
    assert ankudinov_factors(L, B, T, cb, math.inf) == (1.0, 1.0, 1.0, 1.0, 1.0)


def _steady_turn_diameter(depth_ratio, rudder_deg):
    ship = load_ship("s175_003.yaml")
    if depth_ratio is not None:
        ship.set_depth(depth_ratio * ship.draft)
    ship.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([9.0 * KNOT, 0.0, 0.0]), np.zeros(3)))
    ship.settle_command(Command(0.5, 0.0))
    ship.set_command(Command(0.5, math.radians(rudder_deg)))
    for _ in range(12000):                      # 1200 s: the turn settles within about 600 s
        ship.step(0.1)
    s = ship.state
    return 2.0 * math.hypot(*s.linear_velocity_body[:2]) / abs(s.angular_velocity_body[2])


def test_s175_turns_wider_in_shallow_water_and_as_in_deep_water_beyond_h_over_t_4():
    """10 deg of rudder, 9 kn: the steady turning diameter is the deep-water one for h/T >= 4 and
    grows steadily as the water shoals below h/T = 4 (the whole shallow-water set, tug_dynamics
    README "Shallow water"); measured 1.09, 1.18, 1.26, 1.26 times deep at h/T 3, 2, 1.5, 1.2.
    35 deg: the deep value for h/T >= 4. (The hard-over turn's tactical diameter and advance:
    test_shallow_water.)"""
    deep10 = _steady_turn_diameter(None, 10.0)
    d10 = {r: _steady_turn_diameter(r, 10.0) for r in (6.0, 4.0, 3.0, 2.0, 1.5, 1.2)}
    assert d10[6.0] == pytest.approx(deep10, rel=1e-9) and d10[4.0] == pytest.approx(deep10, rel=1e-9)
    assert deep10 < d10[3.0] < d10[2.0] < d10[1.5] < d10[1.2]
    assert d10[1.2] > 1.2 * deep10
    deep35 = _steady_turn_diameter(None, 35.0)
    assert _steady_turn_diameter(4.0, 35.0) == pytest.approx(deep35, rel=1e-9)


@pytest.mark.xfail(strict=True, reason="the whole shallow-water set (README) gives the S-175's hard-over steady "
                   "diameter 0.98 times its h/T 1.5 value at h/T 1.2 (Esso Osaka: 1.31); open, see the README")
def test_s175_hard_over_steady_diameter_at_h_over_t_1_2_against_esso_osaka():
    """35 deg, 9 kn: the steady diameter at h/T 1.2 against h/T 1.5, 1.15-1.6 times (full-scale
    Esso Osaka trials, Crane 1979, as reported: 1.31; a different ship, hence the wide band)."""
    assert 1.15 < _steady_turn_diameter(1.2, 35.0) / _steady_turn_diameter(1.5, 35.0) < 1.6


# ---- the compiled sampler a vessel's step calls ------------------------------------------------
def test_sampler_equals_the_fields_numpy_and_scipy_forms(tmp_path):
    """The one compiled call per step (sea_environment.sampler) against the fields'
    vectorised numpy forms (current, wind), scipy's RegularGridInterpolator (depth) and the
    wind-load, squat and Ankudinov functions composed here by hand, at 200 random states."""
    from sea_environment.shallow_water import ankudinov_factors
    from sea_environment.sampler import (E_APPARENT_ANGLE, E_APPARENT_SPEED, E_CLEARANCE, E_CURRENT_X,
                                         E_CURRENT_Y, E_DEPTH, E_F_NR, E_F_NV, E_F_YR, E_F_YV, E_GROUND_FX,
                                         E_GROUND_FY, E_GROUNDED, E_SQUAT, E_WIND_FX, E_WIND_FY, E_WIND_X,
                                         E_WIND_Z, EnvironmentSampler)
    grid = wavy_grid_file(tmp_path, 9, 7, (-450, -350), 100, 4.0, 3.0, 0.4, 0.3)
    env = Environment.from_mapping({
        "wind": {"speed_kn": 30.0, "from_deg": 200.0, "gusts": True, "seed": 3},
        "current": {"speed_kn": 2.5, "towards_deg": 70.0, "shear_per_s": 0.001, "tidal_period_s": 3000.0},
        "depth": {"grid": str(grid)}})
    w = Windage("tender", 40.0, 110.0, 1.5, 2.5, 28.0)
    length, beam, draft, volume = 28.0, 9.0, 3.0, 400.0
    sampler = EnvironmentSampler(env, length=length, beam=beam, draft=draft, volume=volume, windage=w,
                                       ground_friction=0.4, ground_slip=0.05)
    rng = np.random.default_rng(7)
    grounded = 0
    for _ in range(200):
        t, x, y = rng.uniform(0, 4000), rng.uniform(-600, 600), rng.uniform(-500, 500)
        yaw, u, v = rng.uniform(-math.pi, math.pi), rng.uniform(-2, 6), rng.uniform(-1, 1)
        sampler.time = t
        e = sampler.sample(x, y, yaw, u, v)
        cur = env.current_velocity(t, np.array([x]), np.array([y]))[0]
        h = float(env.depth.grid._interp(np.array([[min(max(y, -300.0), 300.0), min(max(x, -400.0), 400.0)]]))[0])
        vx, vy = math.cos(yaw) * u - math.sin(yaw) * v, math.sin(yaw) * u + math.cos(yaw) * v
        speed, angle = apparent_wind(env.wind_velocity(t), (vx, vy), yaw)
        fx, fy, xp, zp, _ = wind_wrench_body(speed, angle, w)
        sq = squat(math.hypot(vx - cur[0], vy - cur[1]), max(h, draft), length, volume)
        factors = ankudinov_factors(length, beam, draft, volume / (length * beam * draft), max(h, 1e-3))[:4]
        assert [e[E_CURRENT_X], e[E_CURRENT_Y]] == pytest.approx(cur, abs=1e-12)
        assert [e[E_APPARENT_SPEED], e[E_APPARENT_ANGLE]] == pytest.approx([speed, angle], abs=1e-12)
        assert [e[E_WIND_FX], e[E_WIND_FY]] == pytest.approx(
            [math.cos(yaw) * fx - math.sin(yaw) * fy, math.sin(yaw) * fx + math.cos(yaw) * fy], rel=1e-12, abs=1e-9)
        assert [e[E_WIND_X], e[E_WIND_Z]] == pytest.approx([xp, zp], rel=1e-12)
        assert [e[E_DEPTH], e[E_SQUAT], e[E_CLEARANCE]] == pytest.approx([h, sq, h - draft - sq], abs=1e-9)
        assert [e[E_F_YV], e[E_F_YR], e[E_F_NV], e[E_F_NR]] == pytest.approx(factors, rel=1e-9)
        assert bool(e[E_GROUNDED]) == (h - draft - sq < 0.0)
        if e[E_GROUNDED]:
            grounded += 1
            normal = 1025.0 * 9.80665 * (1.0 + 2.0 * volume / (length * beam * draft)) / 3.0 * length * beam \
                * (draft + sq - h)
            friction = 0.4 * normal * min(1.0, math.hypot(vx, vy) / 0.05)
            assert math.hypot(e[E_GROUND_FX], e[E_GROUND_FY]) == pytest.approx(friction, rel=1e-9)
            assert e[E_GROUND_FX] * vx + e[E_GROUND_FY] * vy <= 0.0     # it opposes the motion
        else:
            assert e[E_GROUND_FX] == e[E_GROUND_FY] == 0.0
    assert 10 < grounded < 190      # both branches taken
