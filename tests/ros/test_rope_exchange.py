"""The vessel-rope exchange through the runner, recorded (issue 30 item 4): the rope's force is
followed along the vessel's motion inside each step (rope_model.end_coupling), so a damped system
stays damped at every exchange rate the schema allows. The ROS-free loop of the same physics:
tests/physics/test_rope_coupling.py.

- Bollard pull of the ASD tug on 40 m of steel wire (scenario bollard_pull_wire_40m) at 10, 20
  and 50 Hz: the surge swing of /wire/state's end a force dies out (the propellers damp it) and
  the tension settles at the tug's bollard pull, at every rate. (Before: parted at 10 and 20 Hz.)
- A snatch between two free ASD tugs (engines stopped) on a 40 m wire stretched 0.3 m, at the
  lowest rate the scenario check allows (omega h = 0.5): the recorded energy (both tugs' kinetic
  energy from /<tug>/odom and the ship model's mass matrix, the rope's from /wire/state) never
  ends above where it started and overshoots by at most (omega h)^2.
- The check itself: below that rate the scenario is refused naming the rope and the rate it
  needs; close above it, a warning.
"""
import math
import os

import numpy as np
import pytest
import yaml

from conftest import record_scenario

pytestmark = [pytest.mark.ros, pytest.mark.timeout(600)]
TF = 9806.65


def _share(*parts):
    from ament_index_python.packages import get_package_share_directory
    return os.path.join(get_package_share_directory(parts[0]), *parts[1:])


def _run(path, out, *extra):
    return record_scenario(path, out, *extra, timeout=500)


def _decoded(path, topics):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    out = {t: [] for t in topics}
    with open(path, "rb") as f:
        for _s, channel, _m, msg in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages(
                topics=topics):
            out[channel.topic].append(msg)
    return out


def _t(msg):
    return msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec


@pytest.mark.parametrize("rate", [10.0, 20.0, 50.0])
def test_bollard_pull_surge_swing_decays(rate, tmp_path, ros_domain):
    sc = yaml.safe_load(open(_share("scenario_runner", "scenarios", "bollard_pull_wire_40m.yaml")))
    sc["exchange_rate"] = rate
    path = tmp_path / "bollard.yaml"
    path.write_text(yaml.safe_dump(sc))
    proc = _run(path, tmp_path / "bollard.mcap")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    states = _decoded(tmp_path / "bollard.mcap", ["/wire/state"])["/wire/state"]
    assert not states[-1].broken
    t = np.array([_t(m) for m in states])
    tension = np.array([math.sqrt(m.end_a_force.x ** 2 + m.end_a_force.y ** 2 + m.end_a_force.z ** 2) for m in states])
    assert t[-1] == pytest.approx(120.0)

    def swing(t0, t1):
        sel = (t >= t0) & (t < t1)
        return 0.5 * (tension[sel].max() - tension[sel].min())
    assert swing(0.0, 20.0) > 20 * TF                  # a real snatch at the start
    assert swing(100.0, 120.0) < 0.15 * swing(0.0, 20.0)
    # the settled tension is the tug's bollard pull: its thrust at full ahead and u = 0
    from tug_dynamics.ship_file import load_ship
    from tug_dynamics.vessel import Command
    tug = load_ship(_share("tug_dynamics", "ships", "asd_tug.yaml"))
    tug.settle_command(Command(1.0, 0.0))
    tug.step(1e-3, [])
    assert tension[t >= 100.0].mean() == pytest.approx(tug.status().thrust, rel=0.02)


def _snatch_scenario(tmp_path, rate):
    wire = yaml.safe_load(open(_share("rope_model", "ropes", "steel_wire_40mm.yaml")))
    wire["length"] = 40.0
    (tmp_path / "wire_40m.yaml").write_text(yaml.safe_dump(wire))
    # tug2's bow staple 40.3 m (along the line) behind tug's aft winch: winch_aft (-8, 0, 2.4),
    # bow_staple (14.5, 0, 3.6) of asd_tug.yaml
    gap = math.sqrt(40.3 ** 2 - 1.2 ** 2)
    sc = {"name": "snatch_two_free_tugs", "duration": 40.0, "exchange_rate": rate, "mode": "lockstep",
          "vessels": [{"name": "tug", "ship_file": "asd_tug.yaml", "initial": {"x": 0.0, "y": 0.0}},
                      {"name": "tug2", "ship_file": "asd_tug.yaml", "initial": {"x": -8.0 - gap - 14.5, "y": 0.0}}],
          "ropes": [{"name": "wire", "rope_file": str(tmp_path / "wire_40m.yaml"), "end_a": "tug/winch_aft",
                     "end_b": "tug2/bow_staple", "layout": "straight"}]}
    path = tmp_path / f"snatch_{rate:.4f}.yaml"
    path.write_text(yaml.safe_dump(sc))
    return path


def _omega():
    """omega of the snatch's stiffest vessel-rope mode (the scenario check's formula and inputs)."""
    from rope_model.end_coupling import exchange_omega
    from tug_dynamics.ship_file import load_ship
    tug = load_ship(_share("tug_dynamics", "ships", "asd_tug.yaml"))
    lam = tug.point_mobility(tug.attachments["winch_aft"]) + tug.point_mobility(tug.attachments["bow_staple"])
    return exchange_omega(6.56e7, 40.0, lam, 0.0)


def _rate_for(omega, omega_h):
    """The lowest exchange rate with a whole-nanosecond period (the schema's rule) at which
    omega h <= omega_h."""
    return 1e9 / math.floor(1e9 * omega_h / omega)


def test_recorded_energy_of_a_snatch_between_two_free_tugs_holds_at_the_lowest_allowed_rate(tmp_path, ros_domain):
    from tug_dynamics.ship_file import load_ship
    from rope_model.end_coupling import REFUSE_OMEGA_H
    omega = _omega()
    rate = _rate_for(omega, REFUSE_OMEGA_H)            # the lowest rate the check allows: 7.07 Hz
    out = tmp_path / "snatch.mcap"
    proc = _run(_snatch_scenario(tmp_path, rate), out)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "warning" in proc.stderr and "omega h = 0.50" in proc.stderr   # above 0.2: said before the run
    msgs = _decoded(out, ["/tug/odom", "/tug2/odom", "/wire/state"])
    mass = load_ship(_share("tug_dynamics", "ships", "asd_tug.yaml")).mass_matrix

    def kinetic(m):
        tw = m.twist.twist
        nu = np.array([tw.linear.x, tw.linear.y, tw.angular.z, tw.angular.x])
        return 0.5 * float(nu @ mass @ nu)
    n = min(len(v) for v in msgs.values())
    assert n == int(round(40.0 * rate)) + 1
    energy = np.array([kinetic(msgs["/tug/odom"][k]) + kinetic(msgs["/tug2/odom"][k])
                       + msgs["/wire/state"][k].kinetic_energy + msgs["/wire/state"][k].potential_energy
                       for k in range(n)])
    e0 = energy[0]
    assert e0 > 50e3                                   # the stretch's elastic energy (0.3 m: about 80 kJ)
    assert energy[-1] <= e0                            # measured 0.88 E0 (ROS-free loop)
    assert energy.max() <= (1.0 + (omega / rate) ** 2) * e0   # measured 1.074 E0
    speeds = [m.twist.twist.linear.x for m in msgs["/tug2/odom"]]
    assert max(speeds) > 0.3                           # the snatch happened: tug2 pulled ahead


def test_an_exchange_rate_too_slow_for_the_rope_is_refused_and_a_marginal_one_warned(tmp_path):
    from scenario_format.scenario import ScenarioError, load_scenario
    omega = _omega()
    with pytest.raises(ScenarioError) as err:
        load_scenario(str(_snatch_scenario(tmp_path, _rate_for(omega, 0.55))))
    text = str(err.value)
    assert "key 'exchange_rate'" in text and "rope 'wire'" in text and f">= {math.ceil(omega / 0.5 * 10) / 10:g} Hz" in text
    sc = load_scenario(str(_snatch_scenario(tmp_path, _rate_for(omega, 0.25))))
    assert any("omega h = 0.25" in w and "rope 'wire'" in w for w in sc.warnings), sc.warnings
    assert load_scenario(str(_snatch_scenario(tmp_path, _rate_for(omega, 0.19)))).warnings == []
