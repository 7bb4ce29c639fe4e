"""Several tugs on one ship through the runner (issue 19): the S-175 turned off its berth by a bow
tug on a line and a stern tug pushing (assist_s175_berth_turn, shortened). The contact node's
force reaches both vessels equal and opposite (their status, in their body axes), is recorded on
/push_aft/state, and the lockstep results of a second run, with every node in one process, are
identical to the first (a repeated run and another layout at once)."""
import math

import numpy as np
import pytest

from conftest import executable_path, reserved_domain
from test_recording import decoded as _decoded

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

SCENARIO = "assist_s175_berth_turn.yaml"
DURATION = 20.0   # s: the push is on from about 5 s
RATE = 20.0
STEPS = int(DURATION * RATE)


def _run(out, *extra):
    import subprocess
    proc = subprocess.run([executable_path("scenario_runner", "run_scenario"), SCENARIO, "--duration", str(DURATION),
                           "--output", str(out), "--quiet", *extra], capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc


def _yaw(odom):
    q = odom.pose.pose.orientation
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _physics(msgs):
    out = {}
    for v in ("ship", "bow_tug", "stern_tug"):
        out[v] = np.array([[m.pose.pose.position.x, m.pose.pose.position.y, _yaw(m), m.twist.twist.linear.x,
                            m.twist.twist.linear.y, m.twist.twist.angular.z] for m in msgs[f"/{v}/odom"]])
    out["contact"] = np.array([[m.step, m.penetration, m.normal_force, m.friction_force, m.force_on_hull.x,
                                m.force_on_hull.y, m.point.x, m.point.y] for m in msgs["/push_aft/state"]])
    out["rope"] = np.array([list(m.connection_tensions) for m in msgs["/bow_line/state"]])
    return out


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("assist")
    out = {}
    with reserved_domain():
        for name, extra in (("first", ()), ("one_process", ("--layout", "one_process"))):
            _run(base / f"{name}.mcap", *extra)
            out[name] = _decoded(base / f"{name}.mcap", [f"/{v}/{t}" for v in ("ship", "bow_tug", "stern_tug")
                                                          for t in ("odom", "status")]
                                 + ["/push_aft/state", "/bow_line/state", "/scenario/events"])
    return out


def test_contact_force_reaches_both_vessels_equal_and_opposite(runs):
    msgs = runs["first"]
    contact = msgs["/push_aft/state"]
    assert [m.step for m in contact] == list(range(STEPS + 1))
    assert contact[0].in_contact is False and contact[-1].in_contact is True
    late = contact[-1]
    assert 20e3 < late.normal_force < 200e3 and 0.0 < late.penetration < 0.5
    assert late.penetration == pytest.approx(-late.gap)
    for vessel, sign in (("ship", 1.0), ("stern_tug", -1.0)):
        odom, status = msgs[f"/{vessel}/odom"], msgs[f"/{vessel}/status"]
        assert list(status[-1].contact_names) == ["push_aft"]
        for k in (STEPS // 2, STEPS):
            # status k reports the force that acted over k-1 -> k: the contact computed at k-1,
            # in the body axes of state k
            c, yaw = contact[k - 1], _yaw(odom[k])
            f = status[k].contact_forces[0]
            world = (math.cos(yaw) * f.x - math.sin(yaw) * f.y, math.sin(yaw) * f.x + math.cos(yaw) * f.y)
            np.testing.assert_allclose(world, (sign * c.force_on_hull.x, sign * c.force_on_hull.y),
                                       rtol=1e-9, atol=1e-6)
            p = status[k].contact_points[0]
            point = c.hull_point_body if vessel == "ship" else c.fender_point_body
            assert (p.x, p.y, p.z) == (point.x, point.y, point.z)
    assert msgs["/bow_tug/status"][-1].contact_names == []
    # the push turns the ship's quarter south while the bow line pulls the bow north: bow swings to port
    ship = msgs["/ship/odom"]
    assert _yaw(ship[-1]) > math.radians(0.3)
    # made and lost alternate (the fender may bounce off once before it settles), ending made
    events = [e for e in msgs["/scenario/events"] if e.kind in ("contact_made", "contact_lost")]
    assert events and all(e.target == "push_aft" for e in events)
    assert [e.kind for e in events] == ["contact_made", "contact_lost"] * (len(events) // 2) + ["contact_made"]


def test_identical_on_a_second_run_in_one_process(runs):
    first = _physics(runs["first"])
    assert first["contact"][-1, 2] > 0
    for other in ("one_process",):
        again = _physics(runs[other])
        for key in first:
            np.testing.assert_array_equal(first[key], again[key], err_msg=f"{other}: {key}")


def test_a_diverging_contact_stops_the_run_naming_the_contact(tmp_path):
    """Issue 30 item 5: a fender damper of 1e10 N s/m (the schema's maximum) got the quarter line
    blamed, or the run ended 0 with the pusher thrown off. Run past the scenario check (which
    refuses it, test_malformed_inputs), the contact node's own guard stops the run at the first
    contact step, before its force is applied: exit 3, naming the contact, both vessels and the
    quantity, and no rope or vessel blamed."""
    import subprocess
    import sys
    import os
    library = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src", "scenario_runner",
                           "scenarios", "assist_s175_push_pull.yaml")
    text = open(library).read()
    text = text.replace("    hull: ship\n", "    hull: ship\n    damping: 1.0e+10\n", 1)
    path = tmp_path / "push_pull_damper_1e10.yaml"
    path.write_text(text)
    bypass = ("import sys; import scenario_format.scenario as s; s._check_contact_exchange = lambda *a, **k: None; "
              "from scenario_runner.run_scenario import main; sys.exit(main(sys.argv[1:]))")
    with reserved_domain():
        proc = subprocess.run([sys.executable, "-c", bypass, str(path), "--duration", "10", "--no-record", "--quiet",
                               "--log-dir", str(tmp_path / "logs")], capture_output=True, text=True, timeout=240)
    err = proc.stderr
    assert proc.returncode == 3, proc.stdout + err
    assert "/push_aft/contact failed at step" in err, err
    assert "contact 'push_aft' (fender stern_tug/bow_fender on the hull of ship) diverged" in err, err
    assert "normal force" in err and "more than a passive fender can" in err, err
    assert "rope" not in err.split("run stopped")[-1].split("\n")[0], err

