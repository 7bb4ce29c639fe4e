"""The runner's recording is what rosbag2's MCAP storage plugin (Jazzy) writes.

A short real run is recorded once; then, with readers that share no code with the recorder:

- every channel carries `offered_qos_profiles` in rosbag2's version-9 YAML (policies by name,
  read back by rosbags' rosbag2 QoS parser) and `topic_type_hash`, the REP-2011 hash of its
  type, equal to the hash rosbags computes from the type's definition and to the hash ROS
  itself announces in discovery (rclpy TopicEndpointInfo of a publisher of that type: the
  C type support's hash);
- the file holds one metadata record "rosbag2" with key "serialized_metadata": rosbag2's
  BagMetadata YAML, version 9, whose message counts, start time and duration equal what the
  mcap library reads from the file's summary, and whose topics, QoS and hashes equal the
  channels';
- that metadata, written out as metadata.yaml next to the file (a rosbag2 bag directory),
  is read by rosbags' rosbag2 reader: it reports the type hashes, counts and ros_distro, and
  every message of the .mcap is found through it (its QoS matches the channels');
- `analyze` reads that directory (through its .mcap file);
- a file without the metadata record (a killed run: it is written on close) still reads.
"""
import shutil
import subprocess
from pathlib import Path

import pytest
import yaml

from conftest import executable_path, record_scenario

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

SCENARIO = "seed000_straight_tow_5kn.yaml"
DURATION = 2.0
BAG_METADATA_KEYS = ["version", "storage_identifier", "duration", "starting_time", "message_count",
                     "topics_with_message_count", "compression_format", "compression_mode", "relative_file_paths",
                     "files", "custom_data", "ros_distro"]  # rosbag2_storage/yaml.hpp, BagMetadata, Jazzy

_recorded = {}


@pytest.fixture
def recording(ros_domain, tmp_path_factory):
    """One short real run, recorded once for the whole module (in the first test's domain)."""
    if "path" not in _recorded:
        out = tmp_path_factory.mktemp("rosbag2") / "tow.mcap"
        record_scenario(SCENARIO, out, "--duration", DURATION, timeout=240)
        _recorded["path"] = out
    return _recorded["path"]


def _summary(path):
    from mcap.reader import make_reader
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        metadata = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
    return summary, metadata


def _typestore():
    """rosbags' Jazzy type store plus this project's tug_msgs, from their .msg files."""
    from ament_index_python.packages import get_package_share_directory
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    store = get_typestore(Stores.ROS2_JAZZY)
    msg_dir = Path(get_package_share_directory("tug_msgs")) / "msg"
    types = {}
    for f in sorted(msg_dir.glob("*.msg")):
        types.update(get_types_from_msg(f.read_text(), f"tug_msgs/msg/{f.stem}"))
    store.register(types)
    return store


def _announced_hashes(context, type_names):
    """type -> the hash ROS announces for a publisher of that type (TopicEndpointInfo)."""
    from rclpy.node import Node
    from recording.mcap_io import message_class
    node = Node("hash_probe", context=context)
    try:
        out = {}
        for i, tname in enumerate(sorted(type_names)):
            topic = f"/hash_probe_{i}"
            node.create_publisher(message_class(tname), topic, 1)
            infos = node.get_publishers_info_by_topic(topic)
            assert infos, topic
            out[tname] = str(infos[0].topic_type_hash)
        return out
    finally:
        node.destroy_node()


def _bag_metadata(metadata):
    records = [m for name, m in metadata if name == "rosbag2"]
    assert len(records) == 1 and list(records[0]) == ["serialized_metadata"], metadata
    return yaml.safe_load(records[0]["serialized_metadata"])


def test_channels_carry_rosbag2_qos_and_the_jazzy_type_hash(recording, rclpy_context):
    from rosbags.rosbag2.metadata import parse_qos
    summary, _ = _summary(recording)
    channels = list(summary.channels.values())
    types = {c.topic: summary.schemas[c.schema_id].name for c in channels}
    store = _typestore()
    announced = _announced_hashes(rclpy_context, set(types.values()))
    for c in channels:
        assert set(c.metadata) == {"offered_qos_profiles", "topic_type_hash"}, c.topic
        profiles = yaml.safe_load(c.metadata["offered_qos_profiles"])
        assert len(profiles) == 1 and isinstance(profiles[0]["history"], str), c.topic  # version 9: names
        (qos,) = parse_qos(c.metadata["offered_qos_profiles"])
        assert qos.history.name != "UNKNOWN" and qos.reliability.name == "RELIABLE", (c.topic, qos)
        assert qos.durability.name in ("VOLATILE", "TRANSIENT_LOCAL"), (c.topic, qos)
        thash = c.metadata["topic_type_hash"]
        assert thash.startswith("RIHS01_") and len(thash) == 7 + 64, (c.topic, thash)
        assert thash == store.hash_rihs01(types[c.topic]), c.topic
        assert thash == announced[types[c.topic]], c.topic
    # the odometry's QoS is the contract's latched state QoS
    odom = yaml.safe_load(next(c for c in channels if c.topic == "/tug/odom").metadata["offered_qos_profiles"])[0]
    assert (odom["reliability"], odom["durability"]) == ("reliable", "transient_local")


def test_rosbag2_metadata_record_holds_the_true_counts(recording):
    from rosbags.rosbag2.metadata import parse_qos
    summary, metadata = _summary(recording)
    meta = _bag_metadata(metadata)
    stats = summary.statistics
    assert list(meta) == BAG_METADATA_KEYS
    assert meta["version"] == 9 and meta["storage_identifier"] == "mcap" and meta["ros_distro"] == "jazzy"
    assert meta["compression_format"] == "" and meta["compression_mode"] == ""
    assert meta["relative_file_paths"] == [recording.name]
    assert meta["message_count"] == stats.message_count > 0
    assert meta["starting_time"] == {"nanoseconds_since_epoch": stats.message_start_time}
    assert meta["duration"] == {"nanoseconds": stats.message_end_time - stats.message_start_time}
    assert meta["duration"]["nanoseconds"] == int(DURATION * 1e9)  # simulation time: steps 0 .. N
    assert meta["files"] == [{"path": recording.name, "starting_time": meta["starting_time"],
                              "duration": meta["duration"], "message_count": stats.message_count}]
    by_topic = {t["topic_metadata"]["name"]: t for t in meta["topics_with_message_count"]}
    channels = {c.topic: c for c in summary.channels.values()}
    assert set(by_topic) == set(channels)
    for topic, c in channels.items():
        t = by_topic[topic]
        assert list(t) == ["topic_metadata", "message_count"]
        assert t["message_count"] == stats.channel_message_counts.get(c.id, 0), topic
        tm = t["topic_metadata"]
        assert list(tm) == ["name", "type", "serialization_format", "offered_qos_profiles", "type_description_hash"]
        assert tm["type"] == summary.schemas[c.schema_id].name and tm["serialization_format"] == "cdr"
        assert tm["type_description_hash"] == c.metadata["topic_type_hash"]
        assert parse_qos(tm["offered_qos_profiles"]) == parse_qos(c.metadata["offered_qos_profiles"])
    assert sum(t["message_count"] for t in by_topic.values()) == meta["message_count"]


def _as_bag_directory(recording, meta, where):
    """rosbag2's layout of the recording: metadata.yaml (what rosbag2 writes next to the file)
    and the .mcap under the name the metadata gives it."""
    bag = where / "tow_bag"
    bag.mkdir()
    shutil.copyfile(recording, bag / meta["relative_file_paths"][0])
    (bag / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": meta}, sort_keys=False))
    return bag


def test_rosbags_reads_the_recording_as_a_rosbag2_bag(recording, tmp_path):
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import Reader
    summary, metadata = _summary(recording)
    meta = _bag_metadata(metadata)
    bag = _as_bag_directory(recording, meta, tmp_path)
    counts = {c.topic: summary.statistics.channel_message_counts.get(c.id, 0) for c in summary.channels.values()}
    hashes = {c.topic: c.metadata["topic_type_hash"] for c in summary.channels.values()}
    with Reader(bag) as reader:
        assert {c.topic: c.digest for c in reader.connections} == hashes
        assert {c.topic: c.msgcount for c in reader.connections} == counts
        assert reader.message_count == summary.statistics.message_count
        assert reader.ros_distro == "jazzy" and not reader.compression_mode  # not compressed by rosbag2
        assert reader.start_time == summary.statistics.message_start_time
        assert reader.end_time == summary.statistics.message_end_time + 1  # rosbags: end exclusive
        assert all(c.msgdef.data for c in reader.connections)  # the schemas of the .mcap found
        # every message of the file comes through the bag's connections (same topic, type, QoS)
        assert sum(1 for _ in reader.messages()) == summary.statistics.message_count
    with AnyReader([bag], default_typestore=_typestore()) as reader:
        decoded = 0
        for conn, _t, raw in reader.messages():
            reader.deserialize(raw, conn.msgtype)
            decoded += 1
        assert decoded == summary.statistics.message_count


def test_analyze_reads_the_bag_directory_through_its_mcap(recording, tmp_path):
    _, metadata = _summary(recording)
    bag = _as_bag_directory(recording, _bag_metadata(metadata), tmp_path)
    out = tmp_path / "analysis"
    proc = subprocess.run([executable_path("recording", "analyze"), str(bag), "-o", str(out), "--no-figures"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert f"reading {bag / recording.name}" in proc.stdout
    assert "vessel tug" in proc.stdout and (out / "summary.json").is_file()


def test_a_killed_run_without_the_metadata_record_still_reads(recording, tmp_path):
    """The metadata record is written on close: a run killed before that leaves a file without
    it (and without summary), which reads as before; a file cut after it keeps it."""
    from recording.mcap_io import McapFile
    summary, _ = _summary(recording)
    (index,) = [i for i in summary.metadata_indexes if i.name == "rosbag2"]
    data = recording.read_bytes()
    full = McapFile(str(recording)).scan()
    assert full.complete and full.rosbag2_metadata()["message_count"] == full.message_count
    end = index.offset + index.length
    data_end = summary.chunk_indexes[-1].chunk_start_offset + summary.chunk_indexes[-1].chunk_length
    killed = data[:index.offset] + data[end:(end + data_end) // 2]  # no metadata record, cut in a chunk
    cut = data[:(end + data_end) // 2]
    for name, content, has_metadata in (("killed", killed, False), ("cut", cut, True)):
        path = tmp_path / f"{name}.mcap"
        path.write_bytes(content)
        mf = McapFile(str(path)).scan()
        assert "truncated" in mf.report() and 0 < mf.message_count < full.message_count, (name, mf.report())
        assert mf.rosbag2_metadata() == (full.rosbag2_metadata() if has_metadata else None), name
