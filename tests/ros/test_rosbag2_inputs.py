"""rosbag2 inputs to `analyze`, and the rosbag2 forms the recorder writes.
DDS-free: bags are written with the rosbags library (an independent rosbag2 writer).

- a sqlite3 bag (a .db3 file, or a rosbag2 directory of one) is refused with exit status 2 and
  a short message naming the file and giving the conversion command, no traceback and no
  "corrupt data" lines; the command given works, and `analyze` reads what it writes;
- a rosbag2 directory in MCAP storage is analysed through its .mcap file; a directory with
  several .mcap files (a split bag) or none is refused with a message saying so;
- the recorder's QoS YAML (rosbag2 metadata version 9) is read back by rosbags' rosbag2 QoS
  parser as the profile it came from, and its BagMetadata YAML parses back to the same data.

The refusals (exit status 2) run the tools' entry functions in this process; the same exit
status through the executables: test_analysis and test_replay.
"""
import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

N = 20


def _odometry(i):
    from nav_msgs.msg import Odometry
    m = Odometry()
    m.header.stamp.sec = i
    m.header.frame_id = "map"
    m.child_frame_id = "tug/base_link"
    m.pose.pose.position.x = 2.0 * i
    m.pose.pose.orientation.w = 1.0
    m.twist.twist.linear.x = 2.0
    return m


def _write_bag(path: Path, storage: str) -> Path:
    """A rosbag2 bag (version 9) of /tug/odom written by rosbags."""
    from rclpy.serialization import serialize_message
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    store = get_typestore(Stores.ROS2_JAZZY)
    plugin = StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        conn = writer.add_connection("/tug/odom", "nav_msgs/msg/Odometry", typestore=store)
        for i in range(N):
            writer.write(conn, i * 10 ** 9, serialize_message(_odometry(i)))
    return path


def _analyze(*args):
    from scenario_runner.run_nodes import executable_path
    return subprocess.run([executable_path("recording", "analyze"), *map(str, args), "--no-figures"],
                          capture_output=True, text=True, timeout=120)


def _refused(run_in_process, tool, *args):
    """`tool args` (analyze with --no-figures) through its entry function, in this process."""
    return run_in_process(tool, *args, *(["--no-figures"] if tool == "analyze" else []))


def _assert_refused_with_the_conversion(proc, named):
    assert proc.returncode == 2, proc.stdout + proc.stderr
    err = proc.stderr
    assert "Traceback" not in err and "corrupt" not in err and "byte 0" not in err, err
    assert len(err.strip().splitlines()) <= 6, err
    assert str(named) in err and "sqlite3" in err, err
    (command,) = [line.strip() for line in err.splitlines() if line.strip().startswith("rosbags-convert ")]
    assert "--dst-storage mcap" in command and "ros2 bag convert" in err
    return command


@pytest.mark.parametrize("given", ["db3_file", "bag_directory"])
def test_a_sqlite3_bag_is_refused_with_a_conversion_that_works(tmp_path, run_in_process, given):
    bag = _write_bag(tmp_path / "sq_bag", "sqlite3")
    (db3,) = bag.glob("*.db3")
    target = db3 if given == "db3_file" else bag
    command = _assert_refused_with_the_conversion(_refused(run_in_process, "analyze", target, "-o", tmp_path / "out"),
                                                  db3)
    assert not (tmp_path / "out").exists()
    # the command given, run as given (rosbags-convert of the pinned rosbags, in this venv)
    argv = shlex.split(command)
    argv[0] = os.path.join(os.path.dirname(sys.executable), "rosbags-convert")
    conv = subprocess.run(argv, capture_output=True, text=True, timeout=120)
    assert conv.returncode == 0, conv.stdout + conv.stderr
    dst = Path(argv[argv.index("--dst") + 1])
    assert (dst / f"{dst.name}.mcap").is_file()
    proc = _analyze(dst, "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert f"vessel tug: {N} states" in proc.stdout and (tmp_path / "out" / "summary.json").is_file()


def test_a_directory_of_loose_db3_files_is_refused_naming_the_file(tmp_path, run_in_process):
    bag = _write_bag(tmp_path / "sq_bag", "sqlite3")
    loose = tmp_path / "loose"
    loose.mkdir()
    (db3,) = bag.glob("*.db3")
    os.link(db3, loose / "run.db3")  # no metadata.yaml: the conversion must start from the file
    command = _assert_refused_with_the_conversion(_refused(run_in_process, "analyze", loose), loose / "run.db3")
    assert f"--src {loose / 'run.db3'}" in command


def test_mcap_bag_directory_is_analysed_through_its_file(tmp_path):
    bag = _write_bag(tmp_path / "mc_bag", "mcap")
    (mcap,) = bag.glob("*.mcap")
    proc = _analyze(bag, "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert f"reading {mcap}" in proc.stdout and f"vessel tug: {N} states" in proc.stdout


def test_split_or_empty_directories_are_refused_saying_why(tmp_path, run_in_process):
    bag = _write_bag(tmp_path / "mc_bag", "mcap")
    (mcap,) = bag.glob("*.mcap")
    split = tmp_path / "split"
    split.mkdir()
    for k in range(2):
        os.link(mcap, split / f"split_{k}.mcap")
    proc = _refused(run_in_process, "analyze", split)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert "split" in proc.stderr and "split_0.mcap" in proc.stderr and "rosbags-convert --src" in proc.stderr
    empty = tmp_path / "empty"
    empty.mkdir()
    proc = _refused(run_in_process, "analyze", empty)
    assert proc.returncode == 2 and str(empty) in proc.stderr and "no .mcap" in proc.stderr, proc.stderr


def test_recorder_qos_yaml_is_rosbag2_version_9():
    from rclpy.duration import Duration
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, LivelinessPolicy, QoSProfile, ReliabilityPolicy
    from rosbags.rosbag2.metadata import parse_qos
    from recording.recorder import qos_yaml
    profiles = [
        QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL),
        QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.BEST_EFFORT,
                   durability=DurabilityPolicy.VOLATILE, liveliness=LivelinessPolicy.MANUAL_BY_TOPIC,
                   deadline=Duration(seconds=1, nanoseconds=5), lifespan=Duration(nanoseconds=7),
                   liveliness_lease_duration=Duration(seconds=3)),
    ]
    for q in profiles:
        text = qos_yaml(q)
        (item,) = yaml.safe_load(text)
        assert all(isinstance(item[k], str) for k in ("history", "reliability", "durability", "liveliness"))
        (back,) = parse_qos(text)
        assert back.history.value == int(q.history) and back.depth == q.depth
        assert back.reliability.value == int(q.reliability) and back.durability.value == int(q.durability)
        assert back.liveliness.value == int(q.liveliness)
        for name in ("deadline", "lifespan", "liveliness_lease_duration"):
            t = getattr(back, name)
            assert t.sec * 10 ** 9 + t.nsec == getattr(q, name).nanoseconds, name
        assert back.avoid_ros_namespace_conventions is False


def test_bag_metadata_yaml_round_trips():
    from rclpy.qos import QoSProfile
    from recording.recorder import bag_metadata, qos_dict, to_yaml, type_hash
    topics = [{"name": "/tug/odom", "type": "nav_msgs/msg/Odometry", "qos": [qos_dict(QoSProfile(depth=1))],
               "hash": type_hash("nav_msgs/msg/Odometry"), "count": 3},
              {"name": "/idle", "type": "std_msgs/msg/String", "qos": [qos_dict(QoSProfile(depth=10))],
               "hash": type_hash("std_msgs/msg/String"), "count": 0}]
    for name in ("run.mcap", "a run: #1.mcap", "true", "1.mcap"):
        meta = bag_metadata(name, topics, 5, 25)
        assert yaml.safe_load(to_yaml(meta)) == meta, name
    assert meta["message_count"] == 3 and meta["duration"] == {"nanoseconds": 20}
    assert topics[0]["hash"].startswith("RIHS01_") and type_hash("no_such_msgs/msg/Nothing") == ""
    empty = bag_metadata("x.mcap", [], None, None)  # no message: rosbag2's values
    assert empty["starting_time"] == {"nanoseconds_since_epoch": 2 ** 63 - 1} and empty["duration"]["nanoseconds"] == 0


def test_replay_refuses_a_sqlite3_bag_the_same_way(tmp_path, run_in_process):
    """replay opens its input as analyze does: a .db3 is refused before any node is made."""
    bag = _write_bag(tmp_path / "sq_bag", "sqlite3")
    (db3,) = bag.glob("*.db3")
    _assert_refused_with_the_conversion(_refused(run_in_process, "replay", bag), db3)
