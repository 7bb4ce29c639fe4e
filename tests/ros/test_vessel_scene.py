"""Frames and scene of a vessel as bytes: tf2_msgs built here is ROS's (type hash), the
TFMessage and MarkerArray writers agree with rclpy's deserializer, and the scene's hull and
attachment points are the ship file's (read here with yaml)."""
import glob
import json
import math
import os

import numpy as np
import pytest
import yaml

pytestmark = pytest.mark.timeout(60)

# REP-2011 hash of tf2_msgs/msg/TFMessage in ROS 2 Jazzy (rosbag2 metadata of real bags, tf2_msgs'
# golden-hash test): the type built in this workspace must be the same type.
JAZZY_TF_MESSAGE_HASH = "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"


def _ships():
    from ament_index_python.packages import get_package_share_directory
    return sorted(glob.glob(os.path.join(get_package_share_directory("tug_dynamics"), "ships", "*.yaml")))


def test_tf2_msgs_is_ros_type():
    from ament_index_python.packages import get_package_share_directory
    with open(os.path.join(get_package_share_directory("tf2_msgs"), "msg", "TFMessage.json")) as f:
        hashes = {h["type_name"]: h["hash_string"] for h in json.load(f)["type_hashes"]}
    assert hashes["tf2_msgs/msg/TFMessage"] == JAZZY_TF_MESSAGE_HASH


def test_tf_message_bytes_decode_with_rclpy():
    from rclpy.serialization import deserialize_message
    from tf2_msgs.msg import TFMessage
    from sim_plumbing import cdr
    frames = [("map", "tug/base_link"), ("tug/base_link", "tug/winch_aft")]
    values = [((1.5, -2.25, 0.125), (0.0, 0.1, 0.2, math.sqrt(1 - 0.05))), ((-7.0, 0.0, 2.2), (0.0, 0.0, 0.0, 1.0))]
    msg = deserialize_message(cdr.TFMessageEncoder(frames).encode(123_456_789_012, values), TFMessage)
    assert len(msg.transforms) == 2
    for t, (parent, child), (p, q) in zip(msg.transforms, frames, values):
        assert (t.header.frame_id, t.child_frame_id) == (parent, child)
        assert (t.header.stamp.sec, t.header.stamp.nanosec) == (123, 456_789_012)
        assert (t.transform.translation.x, t.transform.translation.y, t.transform.translation.z) == p
        r = t.transform.rotation
        assert (r.x, r.y, r.z, r.w) == q


@pytest.mark.parametrize("ship", _ships(), ids=os.path.basename)
def test_scene_is_the_ship_file(ship):
    from rclpy.serialization import deserialize_message
    from visualization_msgs.msg import Marker, MarkerArray
    from sim_math.hull_plan import HullDimensions
    from sim_plumbing.scene import VesselScene
    cfg = yaml.safe_load(open(ship))
    hull = cfg["hull"]
    length = hull.get("length", hull.get("length_overall"))
    attachments = cfg["attachments"]
    scene = VesselScene("v", HullDimensions.from_ship_config(cfg), attachments)
    force = (30_000.0, -40_000.0, 0.0)  # 50 kN
    point = next(iter(attachments.values()))
    msg = deserialize_message(scene.markers(2_000_000_000, 120_000.0, [(point, force)], 1e-4), MarkerArray)
    by_id = {m.id: m for m in msg.markers}
    assert all(m.header.frame_id == "v/base_link" and m.frame_locked for m in msg.markers)
    shell = np.array([(p.x, p.y, p.z) for p in by_id[0].points])
    assert by_id[0].type == Marker.TRIANGLE_LIST and len(shell) % 3 == 0
    # the hull spans the ship file's length, beam and draft (body origin midships on the waterline)
    assert shell[:, 0].min() == pytest.approx(-length / 2) and shell[:, 0].max() == pytest.approx(length / 2)
    assert 2 * np.abs(shell[:, 1]).max() == pytest.approx(hull["beam"])
    assert shell[:, 2].min() == pytest.approx(-hull["draft"])
    # not a box: the plan narrows somewhere along the length (bow, or a barge's raked ends below)
    deck = np.array([(p.x, p.y, p.z) for p in by_id[1].points])
    if cfg["model"] == "planing_6dof" or hull["mass"] / (1025.0 * length * hull["beam"] * hull["draft"]) < 0.85:
        assert np.abs(deck[deck[:, 0] > 0.45 * length, 1]).max() < 0.5 * hull["beam"] / 2
    spheres = sorted((p.x, p.y, p.z) for p in by_id[2].points)
    assert spheres == sorted(tuple(float(c) for c in a) for a in attachments.values())
    rope = by_id[20]
    start, end = [np.array([p.x, p.y, p.z]) for p in rope.points]
    assert tuple(start) == tuple(float(c) for c in point)
    assert np.allclose(end - start, np.array(force) * 1e-4)  # 5 m for 50 kN
    thrust = [m for i, m in by_id.items() if 10 <= i < 20]
    lengths = [m.points[1].x - m.points[0].x for m in thrust]
    assert sum(lengths) == pytest.approx(120_000.0 * 1e-4)
