"""The environment in running scenarios (issue 18): the beam-wind tow crabs, the tidal stream's
turn reverses the crab, a slack steel towline lies on the seabed and is dragged clear, and
`status` reports the apparent wind of the state it is published with. Each run is shared with
test_startup_loads (one run per scenario per session)."""
import math

import numpy as np
import pytest

from test_startup_loads import _read, _recorded, _scenario, _stamp

pytestmark = [pytest.mark.ros]


def _odom(msgs):
    t = np.array([_stamp(m) for m in msgs])
    x = np.array([m.pose.pose.position.x for m in msgs])
    y = np.array([m.pose.pose.position.y for m in msgs])
    q = [m.pose.pose.orientation for m in msgs]
    yaw = np.array([math.atan2(2.0 * (o.w * o.z + o.x * o.y), 1.0 - 2.0 * (o.y * o.y + o.z * o.z)) for o in q])
    u = np.array([m.twist.twist.linear.x for m in msgs])
    v = np.array([m.twist.twist.linear.y for m in msgs])
    return t, x, y, yaw, u, v


def _crab_deg(t, x, y, yaw, t0, t1, lag=5.0):
    """Mean heading minus course over ground (deg, + = heading to port of the course) over
    [t0, t1], the course from the displacement over `lag` seconds."""
    i0, i1 = np.searchsorted(t, t0), np.searchsorted(t, t1)
    k = int(round(lag / (t[1] - t[0])))
    cog = np.arctan2(y[i0:i1] - y[i0 - k:i1 - k], x[i0:i1] - x[i0 - k:i1 - k])
    return math.degrees(np.mean(np.angle(np.exp(1j * (yaw[i0:i1] - cog)))))


@pytest.mark.timeout(600)
def test_beam_wind_tow_crabs_into_the_wind_and_status_reports_the_apparent_wind(ros_domain, tmp_path):
    path = _scenario("env_beam_wind_tow")
    msgs = _read(_recorded(path, tmp_path), ["/tug/odom", "/tug/status"])
    t, x, y, yaw, u, v = _odom(msgs["/tug/odom"])
    # wind from the north, track east: the tug heads north of its course (to port), track held
    crab = _crab_deg(t, x, y, yaw, 200.0, 400.0)
    assert 2.0 < crab < 20.0, f"crab angle {crab:.1f} deg"
    late = (t >= 200.0)
    assert np.abs(y[late]).max() < 30.0, f"off the track by {np.abs(y[late]).max():.1f} m"
    # status: the apparent wind of the published state = the scenario's wind (NPD record from its
    # seed, rebuilt here) minus the tug's velocity over ground from the odometry of the same stamp
    from sea_environment.environment import Environment
    import yaml
    with open(path) as f:
        env = Environment.from_mapping(yaml.safe_load(f)["environment"])
    st = {round(_stamp(m), 6): m for m in msgs["/tug/status"]}
    checked = 0
    for i in range(0, t.size, max(1, t.size // 80)):
        m = st.get(round(t[i], 6))
        if m is None:
            continue
        wx, wy = env.wind.velocity_xy(t[i])
        c, s = math.cos(yaw[i]), math.sin(yaw[i])
        vx, vy = c * u[i] - s * v[i], s * u[i] + c * v[i]
        speed = math.hypot(wx - vx, wy - vy)
        bx, by = c * (wx - vx) + s * (wy - vy), -s * (wx - vx) + c * (wy - vy)
        assert m.apparent_wind_speed == pytest.approx(speed, rel=1e-6)
        assert m.apparent_wind_angle == pytest.approx(math.atan2(-by, -bx), abs=1e-6)
        assert math.isinf(m.water_depth) and not m.grounded
        checked += 1
    assert checked > 50


@pytest.mark.timeout(600)
def test_tidal_stream_turns_the_crab_from_flood_to_ebb(ros_domain, tmp_path):
    """Stream setting north (flood) then south (ebb) across an eastward track: the tug heads into
    it, south of its course on the flood (crab < 0) and north of it on the ebb (crab > 0)."""
    msgs = _read(_recorded(_scenario("env_tidal_stream_tow"), tmp_path), ["/tug/odom"])
    t, x, y, yaw, u, v = _odom(msgs["/tug/odom"])
    flood = _crab_deg(t, x, y, yaw, 60.0, 160.0)
    ebb = _crab_deg(t, x, y, yaw, 320.0, 420.0)
    assert flood < -3.0 and ebb > 3.0, f"crab {flood:.1f} deg on the flood, {ebb:.1f} deg on the ebb"


@pytest.mark.timeout(600)
def test_slack_steel_towline_lies_on_the_seabed_until_dragged_clear(ros_domain, tmp_path):
    """7 m of water, 40 mm wire (radius 0.02 m): the sunk bight rests on the bottom (no element
    centre deeper than the seabed by more than a few mm); while it is dragged along the bottom the
    tug's end carries more than the barge's (friction takes the difference), and the line lifts
    clear once the tow moves."""
    msgs = _read(_recorded(_scenario("env_slack_towline_seabed"), tmp_path), ["/towline/state", "/tug/status"])
    states = msgs["/towline/state"]
    t = np.array([_stamp(m) for m in states])
    t -= t[0]
    zmin = np.array([min(p.position.z for p in m.element_poses) for m in states])
    on_bottom = np.array([sum(p.position.z < -6.9 for p in m.element_poses) for m in states])
    early = (t > 20.0) & (t < 90.0)
    assert zmin.min() > -7.0 - 0.01, f"an element {-7.0 - zmin.min():.3f} m into the seabed"
    assert on_bottom[early].min() >= 10, "the bight does not lie on the bottom"
    ta = np.array([math.hypot(m.end_a_force.x, m.end_a_force.y) for m in states])
    tb = np.array([math.hypot(m.end_b_force.x, m.end_b_force.y) for m in states])
    dragging = (t > 60.0) & (t < 110.0)
    assert np.mean(ta[dragging]) > np.mean(tb[dragging]) + 200.0
    assert on_bottom[t > 140.0].min() < on_bottom[early].min()
    st = msgs["/tug/status"][-1]
    assert st.water_depth == pytest.approx(7.0) and st.under_keel_clearance > 0.0 and not st.grounded


@pytest.mark.timeout(600)
def test_analyze_reports_the_least_under_keel_clearance(ros_domain, tmp_path):
    """analyze's ukc_min and squat_max (a study's measures) against ICORELS by hand (PIANC 2014):
    S = 2.4 V / L^2 Fnh^2 / sqrt(1 - Fnh^2), Fnh = U / sqrt(g h), UKC = h - T - S, with V the ship
    file's mass over its water density and U each recorded status' speed through the water, in
    the 7 m of the slack-towline run."""
    import json

    from recording.analysis import main as analyze
    from test_startup_loads import _ship_file

    recording = _recorded(_scenario("env_slack_towline_seabed"), tmp_path)
    statuses = _read(recording, ["/tug/status"])["/tug/status"]
    ship = _ship_file("harbour_tug.yaml")
    length, draft = ship["hull"]["length"], ship["hull"]["draft"]
    volume = ship["hull"]["mass"] / ship["water_density"]
    depth, g = 7.0, 9.80665

    def squat(speed):
        fnh2 = speed * speed / (g * depth)
        return 2.4 * volume / length ** 2 * fnh2 / math.sqrt(1.0 - fnh2)

    squats = np.array([squat(m.speed_through_water) for m in statuses])
    out = tmp_path / "analysis"
    assert analyze([str(recording), "-o", str(out), "--no-figures", "--quiet"]) == 0
    tug = json.loads((out / "summary.json").read_text())["vessels"]["tug"]
    assert squats.max() > 0.01, "the tug never made way: nothing to check"
    assert tug["squat_max"] == pytest.approx(squats.max(), rel=1e-9)
    assert tug["ukc_min"] == pytest.approx(depth - draft - squats.max(), abs=1e-9)
