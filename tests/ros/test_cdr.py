"""The per-step messages written and read as CDR bytes (sim_plumbing/cdr.py). Truth: rclpy's own
(de)serializer. Every encoder's bytes must decode (rclpy) to exactly the message built field by
field, and every decoder must read back the fields of a message rclpy serialized. Names of
many lengths shift every field after them across alignment boundaries. (Bytes themselves are
not compared: rclpy's serializer leaves padding bytes uninitialised.)"""
import math

import numpy as np
import pytest
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from tug_msgs.msg import AttachmentArray, AttachmentPoint, SimStep, StepDone, VesselStatus

from sim_plumbing import cdr

NAMES = ["", "a", "ab", "abc", "abcd", "abcde", "abcdef", "abcdefg", "towing_hook", "bow_bollard_port"]
STAMP_NS = 1234 * 10 ** 9 + 567891234


def _stamp(header, ns=STAMP_NS):
    header.stamp.sec, header.stamp.nanosec = divmod(ns, 10 ** 9)


@pytest.mark.parametrize("frame, child", [("map", "tug/base_link"), ("", "b"), ("world", ""), ("abcdefg", "x/y")])
def test_odometry(frame, child):
    rng = np.random.default_rng(len(frame) + 7 * len(child))
    p, q, v, w = rng.normal(size=3), rng.normal(size=4), rng.normal(size=3), rng.normal(size=3)
    ref = Odometry(child_frame_id=child)
    ref.header.frame_id = frame
    _stamp(ref.header)
    pose, twist = ref.pose.pose, ref.twist.twist
    pose.position.x, pose.position.y, pose.position.z = p
    pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = q
    twist.linear.x, twist.linear.y, twist.linear.z = v
    twist.angular.x, twist.angular.y, twist.angular.z = w
    got = deserialize_message(cdr.OdometryEncoder(frame, child).encode(STAMP_NS, p, q, v, w), Odometry)
    assert got == ref


@pytest.mark.parametrize("vessel", ["tug", "", "abcdefg"])
@pytest.mark.parametrize("n", [0, 1, 4])
def test_attachment_array_both_ways(vessel, n):
    rng = np.random.default_rng(n)
    names = [NAMES[(3 * i + n) % len(NAMES)] + str(i) for i in range(n)]
    pos, vel, q = rng.normal(size=(n, 3)), rng.normal(size=(n, 3)), rng.normal(size=4)
    ref = AttachmentArray(vessel=vessel, step=2 ** 40 + 17)
    ref.header.frame_id = "map"
    _stamp(ref.header)
    for name, p, v in zip(names, pos, vel):
        pt = AttachmentPoint(name=name)
        pt.position.x, pt.position.y, pt.position.z = p
        pt.velocity.x, pt.velocity.y, pt.velocity.z = v
        pt.orientation.x, pt.orientation.y, pt.orientation.z, pt.orientation.w = q
        ref.points.append(pt)
    data = cdr.AttachmentArrayEncoder("map", vessel, names).encode(STAMP_NS, ref.step, pos, vel, q)
    assert deserialize_message(data, AttachmentArray) == ref
    got = cdr.decode_attachment_array(serialize_message(ref))
    assert (got.stamp_ns, got.step, got.vessel) == (STAMP_NS, ref.step, vessel)
    assert list(got.points) == names
    for name, p, v in zip(names, pos, vel):
        assert got.points[name].position == tuple(p) and got.points[name].velocity == tuple(v)
        assert got.points[name].orientation == tuple(q)


@pytest.mark.parametrize("vessel", NAMES)
def test_vessel_status(vessel):
    rng = np.random.default_rng(len(vessel))
    a, b = rng.normal(size=5), rng.normal(size=6)
    ref = VesselStatus(vessel=vessel, step=987654321, anchor_state=3, girting_warning=True,
                       commands_rejected=7, commands_clamped=4_000_000_000)
    ref.header.frame_id = vessel + "/base_link"
    _stamp(ref.header)
    env = rng.normal(size=5)
    ref.grounded = True
    for key, value in zip(cdr.VESSEL_STATUS_FLOATS_A + cdr.VESSEL_STATUS_FLOATS_B + cdr.VESSEL_STATUS_FLOATS_ENV,
                          list(a) + list(b) + list(env)):
        setattr(ref, key, float(value))
    data = cdr.VesselStatusEncoder(ref.header.frame_id, vessel).encode(STAMP_NS, ref.step, a, 3, b, True, 7,
                                                                        4_000_000_000, env, True)
    assert deserialize_message(data, VesselStatus) == ref
    # without an environment: still air, deep water (infinite depth and clearance), afloat
    plain = deserialize_message(cdr.VesselStatusEncoder(ref.header.frame_id, vessel).encode(
        STAMP_NS, ref.step, a, 3, b, True, 7, 4_000_000_000), VesselStatus)
    assert (plain.apparent_wind_speed, plain.squat, plain.grounded) == (0.0, 0.0, False)
    assert math.isinf(plain.water_depth) and math.isinf(plain.under_keel_clearance)


@pytest.mark.parametrize("frame", NAMES)
def test_wrench_stamped_both_ways(frame):
    rng = np.random.default_rng(len(frame))
    f, m = rng.normal(size=3), rng.normal(size=3)
    ref = WrenchStamped()
    ref.header.frame_id = frame
    _stamp(ref.header)
    ref.wrench.force.x, ref.wrench.force.y, ref.wrench.force.z = f
    ref.wrench.torque.x, ref.wrench.torque.y, ref.wrench.torque.z = m
    assert deserialize_message(cdr.WrenchStampedEncoder(frame).encode(STAMP_NS, f, m), WrenchStamped) == ref
    got = cdr.decode_wrench_stamped(serialize_message(ref))
    assert got == (STAMP_NS, frame, tuple(f), tuple(m)) and got.is_finite()
    ref.wrench.torque.y = float("nan")
    assert not cdr.decode_wrench_stamped(serialize_message(ref)).is_finite()


@pytest.mark.parametrize("node", ["/tug/vessel", "/a", "/towline/rope_node_x"])
@pytest.mark.parametrize("error", ["", "step 5 failed: rope diverged (tension 1e12 N)"])
def test_step_done_both_ways(node, error):
    run = "0123456789abcdef"
    ref = StepDone(run_id=run, node=node, step=123456789012, compute_time=0.000321, ok=not error,
                   refused_messages=3_000_000_000, error=error)
    _stamp(ref.header)
    data = cdr.StepDoneEncoder(node, run).encode(STAMP_NS, ref.step, ref.compute_time, error, 3_000_000_000)
    assert deserialize_message(data, StepDone) == ref
    got = cdr.decode_step_done(serialize_message(ref))
    assert got == (STAMP_NS, run, node, ref.step, ref.compute_time, not error, 3_000_000_000, error)


@pytest.mark.parametrize("ordered", [[], ["tug"], ["barge", "tug", "towline"], NAMES[1:]])
def test_sim_step_both_ways(ordered):
    ref = SimStep(run_id="run-7", step=4321, period=0.02, ordered=ordered)
    _stamp(ref.header)
    ref.time.sec, ref.time.nanosec = divmod(STAMP_NS, 10 ** 9)
    assert deserialize_message(cdr.sim_step_cdr(STAMP_NS, 4321, 0.02, ordered, "run-7"), SimStep) == ref
    assert cdr.decode_sim_step(serialize_message(ref)) == (STAMP_NS, "run-7", 4321, tuple(ordered))


def test_clock():
    ref = Clock()
    ref.clock.sec, ref.clock.nanosec = divmod(STAMP_NS, 10 ** 9)
    assert deserialize_message(cdr.clock_cdr(STAMP_NS), Clock) == ref


def test_truncated_or_foreign_bytes_are_refused_with_a_reason():
    data = serialize_message(WrenchStamped())
    with pytest.raises(cdr.CdrError, match="ends at byte"):
        cdr.decode_wrench_stamped(data[:30])
    with pytest.raises(cdr.CdrError, match="little-endian"):
        cdr.decode_wrench_stamped(b"\x00\x00\x00\x00" + data[4:])


@pytest.mark.parametrize("n, ns, frame", [(12, "towline", "map"), (1, "r", "world"), (0, "", ""), (5, "abcdefg", "m")])
def test_line_strip_marker_array(n, ns, frame):
    from geometry_msgs.msg import Point
    from std_msgs.msg import ColorRGBA
    from visualization_msgs.msg import Marker, MarkerArray
    rng = np.random.default_rng(n)
    pts, cols = rng.normal(size=(n, 3)), rng.random(size=(n, 4))
    m = Marker(ns=ns, id=3, type=Marker.LINE_STRIP, action=Marker.ADD)
    m.header.frame_id = frame
    _stamp(m.header)
    m.pose.orientation.w = 1.0
    m.scale.x = 0.37
    m.points = [Point(x=float(p[0]), y=float(p[1]), z=float(p[2])) for p in pts]
    m.colors = [ColorRGBA(r=float(c[0]), g=float(c[1]), b=float(c[2]), a=float(c[3])) for c in cols]
    # colors are float32 on the wire: the reference goes through rclpy's own round trip
    ref = deserialize_message(serialize_message(MarkerArray(markers=[m])), MarkerArray)
    got = deserialize_message(cdr.line_strip_marker_array_cdr(STAMP_NS, frame, ns, 3, 0.37, pts, cols), MarkerArray)
    assert got == ref
    assert got.markers[0].points == m.points  # float64: exact


def _marker(spec, frame, stamp_ns):
    """The visualization_msgs/Marker a MarkerSpec stands for, built field by field."""
    from geometry_msgs.msg import Point
    from std_msgs.msg import ColorRGBA
    from visualization_msgs.msg import Marker
    m = Marker(ns=spec.ns, id=spec.marker_id, type=spec.marker_type, action=Marker.ADD, text=spec.text,
               frame_locked=spec.frame_locked)
    m.header.frame_id = frame
    _stamp(m.header, stamp_ns)
    p = m.pose
    p.position.x, p.position.y, p.position.z = spec.pose[:3]
    p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w = spec.pose[3:]
    m.scale.x, m.scale.y, m.scale.z = spec.scale
    m.color = ColorRGBA(r=spec.color[0], g=spec.color[1], b=spec.color[2], a=spec.color[3])
    m.points = [Point(x=float(q[0]), y=float(q[1]), z=float(q[2])) for q in np.reshape(spec.points, (-1, 3))]
    m.colors = [ColorRGBA(r=float(c[0]), g=float(c[1]), b=float(c[2]), a=float(c[3]))
                for c in np.reshape(spec.colors, (-1, 4))]
    return m


@pytest.mark.parametrize("frame", ["tug/base_link", "b", "abcdefg/base_link"])
@pytest.mark.parametrize("n_changing", [0, 1, 3])
def test_marker_array_template(frame, n_changing):
    """The fixed markers laid out once and the changing ones after them, at two stamps: rclpy
    reads exactly the array built field by field (names of many lengths move the alignment)."""
    from visualization_msgs.msg import MarkerArray
    rng = np.random.default_rng(len(frame) + n_changing)
    fixed = [cdr.MarkerSpec(name, i, cdr.MARKER_TRIANGLE_LIST if i % 2 else cdr.MARKER_SPHERE_LIST,
                            tuple(rng.random(3)), tuple(rng.random(4)), rng.normal(size=(3 * i + 1, 3)),
                            rng.random(size=(3 * i + 1, 4)) if i % 3 == 0 else (), frame_locked=True)
             for i, name in enumerate(NAMES[:6])]
    fixed.append(cdr.MarkerSpec("tug", 9, cdr.MARKER_TEXT, (0.0, 0.0, 2.5), (1.0, 1.0, 1.0, 1.0),
                                pose=(0.0, 0.0, 7.0, 0.0, 0.0, 0.0, 1.0), text="tug 1", frame_locked=True))
    template = cdr.MarkerArrayTemplate(frame, fixed)
    for stamp_ns in (STAMP_NS, STAMP_NS + 50_000_000):
        changing = [cdr.MarkerSpec(NAMES[j + 4], 20 + j, cdr.MARKER_ARROW, (0.2, 0.4, 0.6), (1.0, 0.5, 0.0, 1.0),
                                   rng.normal(size=(2, 3)), frame_locked=True) for j in range(n_changing)]
        ref = MarkerArray(markers=[_marker(m, frame, stamp_ns) for m in fixed + changing])
        ref = deserialize_message(serialize_message(ref), MarkerArray)  # colors: float32 on the wire
        assert deserialize_message(template.encode(stamp_ns, changing), MarkerArray) == ref


def test_undecodable_bytes_are_reported_and_dropped():
    reasons = []
    bad_name = cdr.StepDoneEncoder("/tug/vessel", "r").encode(STAMP_NS, 1, 0.1).replace(b"/tug/vessel", b"/tug/\xffessel")
    assert cdr.decode_or_report(cdr.decode_step_done, bad_name, reasons.append) is None
    assert cdr.decode_or_report(cdr.decode_sim_step, b"\x00\x01\x00\x00\x01", reasons.append) is None
    assert "not UTF-8" in reasons[0] and "ends at byte" in reasons[1]
    good = cdr.clock_cdr(5)
    assert cdr.decode_or_report(lambda d: cdr.CdrReader(d).stamp_ns(), good, reasons.append) == 5


# -- ASD tug: thruster orders and per-thruster status (issue 19 item 1) --------------------------
@pytest.mark.parametrize("n", [0, 1, 2, 3])
@pytest.mark.parametrize("named", [True, False])
def test_thruster_command_decoded(n, named):
    from tug_msgs.msg import ThrusterCommand
    rng = np.random.default_rng(n)
    names = [NAMES[(2 * i + n) % len(NAMES)] for i in range(n)] if named else []
    ref = ThrusterCommand(thrusters=names, azimuth=rng.normal(size=n).tolist(), rpm=rng.normal(size=n).tolist())
    ref.header.frame_id = NAMES[n]
    _stamp(ref.header)
    got = cdr.decode_thruster_command(serialize_message(ref))
    assert got == (STAMP_NS, tuple(names), tuple(ref.azimuth), tuple(ref.rpm))
    # lengths as sent (the vessel node checks them), NaN as sent (refused there)
    ref.azimuth, ref.rpm = [float("nan")], [0.5, 0.5]
    got = cdr.decode_thruster_command(serialize_message(ref))
    assert math.isnan(got.azimuth[0]) and got.rpm == (0.5, 0.5) and got.thrusters == tuple(names)


def test_thruster_command_garbage_is_refused_with_a_reason():
    from tug_msgs.msg import ThrusterCommand
    data = serialize_message(ThrusterCommand(thrusters=["port", "starboard"], azimuth=[0.1, 0.2], rpm=[0.3, 0.4]))
    for end in range(len(data)):
        with pytest.raises(cdr.CdrError):
            cdr.decode_thruster_command(data[:end])
    huge = bytearray(data)
    huge[20:24] = (2 ** 32 - 1).to_bytes(4, "little")  # thrusters' count (after the stamp and frame_id "")
    with pytest.raises(cdr.CdrError, match="does not fit"):
        cdr.decode_thruster_command(bytes(huge))
    rng = np.random.default_rng(5)
    for _ in range(2000):  # random bytes: decoded or refused, never another exception
        try:
            cdr.decode_thruster_command(b"\x00\x01\x00\x00" + rng.bytes(int(rng.integers(0, 80))))
        except cdr.CdrError:
            pass


@pytest.mark.parametrize("vessel", ["tug", "", "abcdefg"])
@pytest.mark.parametrize("n", [0, 1, 2, 3])
def test_thruster_status(vessel, n):
    from tug_msgs.msg import ThrusterStatus
    rng = np.random.default_rng(n + len(vessel))
    names = [NAMES[(3 * i + n) % len(NAMES)] for i in range(n)]
    columns = rng.normal(size=(len(cdr.ThrusterStatusEncoder.FIELDS), n))
    ref = ThrusterStatus(step=2 ** 40 + 3, vessel=vessel, names=names)
    ref.header.frame_id = vessel + "/base_link"
    _stamp(ref.header)
    for field, column in zip(cdr.ThrusterStatusEncoder.FIELDS, columns):
        setattr(ref, field, column.tolist())
    data = cdr.ThrusterStatusEncoder(ref.header.frame_id, vessel, names).encode(STAMP_NS, ref.step, columns.tolist())
    assert deserialize_message(data, ThrusterStatus) == ref


@pytest.mark.parametrize("mode, rate, ts, tr, tb", [(0, 1.5, 0.0, 0.0, 0.0), (1, 0.0, 0.0, 0.0, 9.0e4),
                                                    (2, -0.5, 8.0e4, 1.5e4, 0.0)])
def test_winch_command_reads_back(mode, rate, ts, tr, tb):
    from tug_msgs.msg import WinchCommand
    ref = WinchCommand(payout_rate=rate, mode=mode, set_tension=ts, recover_tension=tr, brake_load=tb)
    ref.header.frame_id = "abc"
    _stamp(ref.header)
    got = cdr.decode_winch_command(serialize_message(ref))
    assert got == (STAMP_NS, rate, mode, ts, tr, tb)
    assert WinchCommand.SPEED == 0 and WinchCommand.HOLD == 1 and WinchCommand.CONSTANT_TENSION == 2


def test_winch_command_of_the_old_layout_is_a_speed_order():
    # the message before the winch modes ended after payout_rate: SPEED, every tension 0 (keep)
    from tug_msgs.msg import WinchCommand
    ref = WinchCommand(payout_rate=-2.0)
    _stamp(ref.header)
    data = serialize_message(ref)
    old = data[:4 + 8 + 4 + 4 + 8]  # encapsulation, stamp, frame_id "" (4 + 1, padded), payout_rate
    got = cdr.decode_winch_command(old)
    assert (got.payout_rate, got.mode, got.set_tension, got.recover_tension, got.brake_load) == (-2.0, 0, 0.0, 0.0, 0.0)


@pytest.mark.parametrize("names", [(), ("a",), ("push_aft", "ab"), ("abc", "abcd", "abcdefg")])
def test_vessel_status_contacts(names):
    """The contact arrays after the fixed fields, for 0..3 contacts (names shift the arrays
    across alignment boundaries)."""
    rng = np.random.default_rng(len(names))
    a, b, env = rng.normal(size=5), rng.normal(size=6), rng.normal(size=5)
    forces, points = rng.normal(size=3 * len(names)), rng.normal(size=3 * len(names))
    data = cdr.VesselStatusEncoder("s/base_link", "s", names).encode(
        STAMP_NS, 5, a, 1, b, False, 0, 0, env, False, forces, points)
    got = deserialize_message(data, VesselStatus)
    assert list(got.contact_names) == list(names)
    assert [c for v in got.contact_forces for c in (v.x, v.y, v.z)] == list(forces)
    assert [c for p in got.contact_points for c in (p.x, p.y, p.z)] == list(points)
    assert got.squat == env[3] and got.step == 5


@pytest.mark.parametrize("names", [("c", "t", "f", "h"), ("push_aft", "tug2", "bow_fender", "ship"),
                                   ("abcdefg", "ab", "abc", "abcd")])
def test_hull_contact_both_ways(names):
    from tug_msgs.msg import HullContact
    rng = np.random.default_rng(len("".join(names)))
    values, vectors = rng.normal(size=4), rng.normal(size=12)
    ref = HullContact(step=42, contact=names[0], fender_vessel=names[1], fender=names[2], hull_vessel=names[3],
                      in_contact=True, penetration=values[0], gap=values[1], normal_force=values[2],
                      friction_force=values[3])
    ref.header.frame_id = "map"
    _stamp(ref.header)
    for i, field in enumerate(("force_on_hull", "point", "hull_point_body", "fender_point_body")):
        msg = getattr(ref, field)
        msg.x, msg.y, msg.z = vectors[3 * i:3 * i + 3]
    data = cdr.HullContactEncoder("map", *names).encode(STAMP_NS, 42, True, values, vectors)
    assert deserialize_message(data, HullContact) == ref
    got = cdr.decode_hull_contact(serialize_message(ref))
    assert (got.stamp_ns, got.step, got.contact, got.fender_vessel, got.fender, got.hull_vessel, got.in_contact) == (
        STAMP_NS, 42, *names, True)
    assert got.values == tuple(values) and got.force_on_hull + got.point + got.hull_point_body + \
        got.fender_point_body == tuple(vectors)


@pytest.mark.parametrize("vessel, attachment", [("tug", "winch_aft"), ("t", "b"), ("barge_long_name", "bow")])
def test_rope_end_coupling_both_ways(vessel, attachment):
    from tug_msgs.msg import RopeEndCoupling
    rng = np.random.default_rng(len(vessel) + 7 * len(attachment))
    v = rng.normal(size=27)
    ref = RopeEndCoupling(step=7, vessel=vessel, attachment=attachment, stiffness=list(v[9:18]),
                          damping=list(v[18:27]))
    ref.header.frame_id = "map"
    _stamp(ref.header)
    ref.force.x, ref.force.y, ref.force.z = v[0:3]
    ref.reference_position.x, ref.reference_position.y, ref.reference_position.z = v[3:6]
    ref.reference_velocity.x, ref.reference_velocity.y, ref.reference_velocity.z = v[6:9]
    data = cdr.RopeEndCouplingEncoder("map", vessel, attachment).encode(
        STAMP_NS, 7, v[0:3], v[3:6], v[6:9], v[9:18].reshape(3, 3), v[18:27].reshape(3, 3))
    assert deserialize_message(data, RopeEndCoupling) == ref
    got = cdr.decode_rope_end_coupling(serialize_message(ref))
    assert (got.stamp_ns, got.step, got.vessel, got.attachment) == (STAMP_NS, 7, vessel, attachment)
    assert got.force + got.reference_position + got.reference_velocity + got.stiffness + got.damping == tuple(v)
    assert got.is_finite()


@pytest.mark.parametrize("frame, child", [("map", "tug/base_link"), ("", "b"), ("abcdefg", "x/y")])
def test_decode_odometry(frame, child):
    rng = np.random.default_rng(len(frame) + 3 * len(child))
    v = rng.normal(size=13)
    ref = Odometry(child_frame_id=child)
    ref.header.frame_id = frame
    _stamp(ref.header)
    p, o, t = ref.pose.pose.position, ref.pose.pose.orientation, ref.twist.twist
    p.x, p.y, p.z, o.x, o.y, o.z, o.w = v[:7]
    t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z = v[7:]
    ref.pose.covariance = list(rng.normal(size=36))
    got = cdr.decode_odometry(serialize_message(ref))
    assert (got.stamp_ns, got.frame_id, got.child_frame_id) == (STAMP_NS, frame, child)
    assert got.position + got.orientation + got.linear + got.angular == tuple(v)
