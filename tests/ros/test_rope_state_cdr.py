"""The rope node writes tug_msgs/RopeState as CDR bytes straight from numpy arrays
(rope_model/state_cdr.py). Truth: rclpy's own deserializer must read back exactly the message
built field by field, for any element count, broken ropes and empty arrays. (Bytes are not
compared: rclpy's serializer leaves padding bytes uninitialised.)"""
import numpy as np
import pytest
from geometry_msgs.msg import Pose, Twist
from rclpy.serialization import deserialize_message, serialize_message
from tug_msgs.msg import RopeState

from rope_model.state_cdr import rope_state_cdr


def _reference(d) -> RopeState:
    m = RopeState(step=d["step"], rope=d["rope"], model=d["model"])
    m.header.stamp.sec, m.header.stamp.nanosec = divmod(d["stamp_ns"], 10 ** 9)
    m.header.frame_id = d["frame_id"]
    for p, q, v, w in zip(d["positions"], d["quaternions"], d["velocities"], d["angular_velocities"]):
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = map(float, p)
        pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = map(float, q)
        twist = Twist()
        twist.linear.x, twist.linear.y, twist.linear.z = map(float, v)
        twist.angular.x, twist.angular.y, twist.angular.z = map(float, w)
        m.element_poses.append(pose)
        m.element_velocities.append(twist)
    m.element_lengths = [float(x) for x in d["lengths"]]
    m.connection_tensions = [float(x) for x in d["tensions"]]
    m.piece_starts = [int(x) for x in d["piece_starts"]]
    m.unstretched_length, m.stretched_length, m.mass = d["unstretched_length"], d["stretched_length"], d["mass"]
    m.end_a_force.x, m.end_a_force.y, m.end_a_force.z = map(float, d["end_a_force"])
    m.end_b_force.x, m.end_b_force.y, m.end_b_force.z = map(float, d["end_b_force"])
    m.broken = d["broken"]
    m.kinetic_energy, m.potential_energy = d["kinetic_energy"], d["potential_energy"]
    return m


@pytest.mark.parametrize("n, starts, broken, name, frame", [
    (11, [0], False, "towline", "map"), (1, [0], True, "r", "map"), (50, [0, 17, 33], True, "a_long_rope_name", "world"),
    (0, [], False, "", ""), (7, [0, 3], False, "ab", "m")])
def test_rope_state_bytes_decode_to_the_same_message(n, starts, broken, name, frame):
    rng = np.random.default_rng(n)
    d = dict(stamp_ns=1234 * 10 ** 9 + 567891234, frame_id=frame, step=61717, rope=name, model="element_chain",
             positions=rng.normal(size=(n, 3)), quaternions=rng.normal(size=(n, 4)),
             velocities=rng.normal(size=(n, 3)), angular_velocities=rng.normal(size=(n, 3)),
             lengths=rng.random(n), tensions=rng.random(n + 1) if n else np.zeros(0), piece_starts=starts,
             unstretched_length=100.0, stretched_length=100.37, mass=172.5,
             end_a_force=rng.normal(size=3), end_b_force=rng.normal(size=3), broken=broken,
             kinetic_energy=float(rng.random()), potential_energy=float(rng.normal()))
    ref = _reference(d)
    got = deserialize_message(rope_state_cdr(**d), RopeState)
    assert got == ref
    # and the reference survives rclpy's own round trip (the comparison itself is sound)
    assert deserialize_message(serialize_message(ref), RopeState) == ref
