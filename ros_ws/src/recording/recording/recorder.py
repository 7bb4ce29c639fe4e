"""Records topics to one MCAP file the way rosbag2 does, so `ros2 bag play`, Foxglove and the
`rosbags` / `mcap-ros2-support` readers open it:

- profile "ros2"; one schema per type, encoding "ros2msg", holding the type's .msg text
  followed by every dependency ("=" * 80, "MSG: pkg/Type", its text), as rosbag2 writes it;
- channels with message encoding "cdr", the publisher's offered QoS in the channel metadata
  key "offered_qos_profiles" (rosbag2's YAML, metadata version 9: policies by name) and the
  type's hash in "topic_type_hash" (REP-2011 "RIHS01_<sha256>", read from the type
  description the ROS build generated: share/<pkg>/msg/<Type>.json);
- messages are the serialized CDR bytes as received (no re-serialisation); log time = the
  simulation time stamp of the step (receive order kept), publish time the same;
- the per-step outputs of the nodes the scenario runner started come through their feed
  (sim_plumbing/record_feed.py: the bytes each node publishes, handed over by a pipe or, in one
  process, a call) instead of a second DDS delivery; every other topic by subscription. The
  outputs of nodes the runner did not start (`run_scenario --external`, e.g. on other PCs) are
  subscribed and logged at the simulation time they are stamped with (`by_stamp`), however late
  the network delivers them; the runner waits for each step's (lagging()) before the next;
- chunked, with a summary section (statistics, chunk and message indexes) written on close,
  also after Ctrl-C;
- on close, like rosbag2's MCAP storage plugin (Jazzy), a metadata record "rosbag2" whose key
  "serialized_metadata" holds the bag's metadata (rosbag2 BagMetadata YAML, version 9: storage
  mcap, start time and duration, message counts per topic, QoS, type hashes, ros_distro), so
  `ros2 bag info` / `ros2 bag play` read the file as one of theirs. A run killed before close
  leaves a file without it (and without summary), which the tolerant reader (mcap_io) reads.
"""
from __future__ import annotations

import fcntl
import json
import os
import re
import struct
from typing import Callable, Dict, List, Optional, Tuple

import yaml
from mcap.data_stream import RecordBuilder
from mcap.records import DataEnd, Footer
from mcap.writer import MCAP0_MAGIC, CompressionType, Writer
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile

from rclpy.serialization import deserialize_message

from recording.mcap_io import ros_decode_errors
from sim_plumbing.msg_definitions import message_definition  # noqa: F401 - the recorder's schemas
from sim_plumbing.record_feed import PipeReader
from sim_plumbing.stepping import RateLimitedLog

BAG_METADATA_VERSION = 9  # rosbag2 Jazzy
ROS_DISTRO = "jazzy"  # the ROS 2 wheels this project runs on; ROS_DISTRO in the environment wins
INT64_MAX = 2 ** 63 - 1  # rosbag2's starting time of a bag without messages


def _policy_name(policy) -> str:
    """rmw's name of a QoS policy value ("keep_last", "reliable", "transient_local", ...)."""
    return policy.name.lower()


def qos_dict(qos: QoSProfile) -> dict:
    """One offered QoS profile the way rosbag2 (metadata version 9) serialises it."""
    def dur(d):
        return {"sec": d.nanoseconds // 10 ** 9, "nsec": d.nanoseconds % 10 ** 9}
    return {"history": _policy_name(qos.history), "depth": int(qos.depth),
            "reliability": _policy_name(qos.reliability), "durability": _policy_name(qos.durability),
            "deadline": dur(qos.deadline), "lifespan": dur(qos.lifespan), "liveliness": _policy_name(qos.liveliness),
            "liveliness_lease_duration": dur(qos.liveliness_lease_duration),
            "avoid_ros_namespace_conventions": bool(qos.avoid_ros_namespace_conventions)}


def to_yaml(value) -> str:
    """Block-style YAML (rosbag2 reads it with yaml-cpp, which takes any YAML 1.2 layout)."""
    return yaml.safe_dump(value, sort_keys=False, default_flow_style=False, allow_unicode=True, width=1 << 30)


def qos_yaml(qos: QoSProfile) -> str:
    """The offered QoS as rosbag2 (Jazzy) stores it in the channel metadata."""
    return to_yaml([qos_dict(qos)])


_hashes: Dict[str, str] = {}


def type_hash(full_type: str) -> str:
    """The REP-2011 type hash ("RIHS01_<64 hex>") of e.g. 'nav_msgs/msg/Odometry', from the type
    description the ROS build generated (rosidl_generator_type_description writes
    share/<pkg>/msg/<Type>.json); "" if there is none (what rosbag2 records when it cannot
    know the hash)."""
    if full_type not in _hashes:
        pkg, sub, name = full_type.split("/")
        found = ""
        try:
            from ament_index_python.packages import get_package_share_directory
            with open(os.path.join(get_package_share_directory(pkg), sub, name + ".json")) as f:
                for entry in json.load(f).get("type_hashes", []):
                    if entry.get("type_name") == full_type:
                        found = str(entry.get("hash_string", ""))
                        break
        except (OSError, ValueError, LookupError, AttributeError):
            found = ""
        _hashes[full_type] = found if re.fullmatch(r"RIHS01_[0-9a-f]{64}", found) else ""
    return _hashes[full_type]


def bag_metadata(file_name: str, topics: List[dict], start_ns: Optional[int], end_ns: Optional[int]) -> dict:
    """rosbag2's BagMetadata (version 9) of a one-file MCAP bag, keys in rosbag2's order.
    topics: {"name", "type", "qos": [qos_dict], "hash", "count"} in creation order."""
    count = sum(t["count"] for t in topics)
    start = INT64_MAX if start_ns is None else int(start_ns)
    duration = 0 if start_ns is None or end_ns is None else int(end_ns - start_ns)
    return {
        "version": BAG_METADATA_VERSION,
        "storage_identifier": "mcap",
        "duration": {"nanoseconds": duration},
        "starting_time": {"nanoseconds_since_epoch": start},
        "message_count": count,
        "topics_with_message_count": [
            {"topic_metadata": {"name": t["name"], "type": t["type"], "serialization_format": "cdr",
                                "offered_qos_profiles": t["qos"], "type_description_hash": t["hash"]},
             "message_count": t["count"]} for t in topics],
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [file_name],
        "files": [{"path": file_name, "starting_time": {"nanoseconds_since_epoch": start},
                   "duration": {"nanoseconds": duration}, "message_count": count}],
        "custom_data": None,
        "ros_distro": os.environ.get("ROS_DISTRO") or ROS_DISTRO,
    }


RESERVE_BYTES = 64 * 1024  # kept free beside a recording: room to end it readably on a full disk


class RecordingInUse(OSError):
    """Another process (a run still going) has claimed this recording's path."""


class OutputClaim:
    """A recording's path claimed by this process for as long as it writes it: an exclusive lock
    on `.<name>.lock` beside it (holding the pid), taken before the recording is opened, so that a
    second run given the same --output is refused before it truncates or removes the first run's
    file. The kernel drops the lock with the process, however it ends (a stale lock file is taken
    over)."""

    def __init__(self, path: str):
        folder = os.path.dirname(os.path.abspath(path))
        os.makedirs(folder, exist_ok=True)
        self.lock_path = os.path.join(folder, f".{os.path.basename(path)}.lock")
        while True:
            fd = os.open(self.lock_path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
                os.close(fd)
                raise RecordingInUse(f"{os.path.abspath(path)} is being written by another run (pid {holder}); "
                                     f"give this run another --output") from None
            try:
                same = os.fstat(fd).st_ino == os.stat(self.lock_path).st_ino
            except FileNotFoundError:
                same = False
            if same:  # not a lock file its last holder removed while we waited for it
                break
            os.close(fd)
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        self._fd = fd

    def release(self) -> None:
        if self._fd is not None:
            try:
                os.remove(self.lock_path)
            except OSError:
                pass
            os.close(self._fd)
            self._fd = None


class RecordingFile:
    """The stream the mcap Writer writes to: unbuffered, so each write (the Writer hands over
    whole records) is on disk or has failed, and `good` is the offset after the last complete
    one. A reserve file beside it keeps RESERVE_BYTES free: when the disk fills (or the file
    system fails) mid-run, end_readably() frees the reserve, cuts the file back to its last
    complete record and closes the data section (DataEnd, a Footer without summary), which
    every MCAP reader takes: the run stops, the recording up to there stays usable."""

    def __init__(self, path: str, claim: Optional[OutputClaim] = None):
        self.path = path
        self.claim = claim or OutputClaim(path)  # RecordingInUse before anything of the path is touched
        self.reserve_path = os.path.join(os.path.dirname(os.path.abspath(path)), f".{os.path.basename(path)}.reserve")
        try:
            self._f = open(path, "wb", buffering=0)
        except OSError:
            self.claim.release()
            raise
        self.good = 0
        self.ended = False
        try:
            with open(self.reserve_path, "wb") as reserve:
                reserve.write(b"\0" * RESERVE_BYTES)
        except OSError:
            self._f.close()
            self._drop_reserve()
            self.claim.release()
            raise

    def write(self, data) -> int:
        view = memoryview(data)
        done = 0
        while done < len(view):
            done += self._f.write(view[done:])  # OSError (ENOSPC, EIO, ...) leaves `good` as it was
        self.good += done
        return done

    def tell(self) -> int:
        return self.good

    def flush(self) -> None:
        pass  # unbuffered

    def _drop_reserve(self) -> None:
        try:
            os.remove(self.reserve_path)
        except OSError:
            pass

    def end_readably(self) -> None:
        """After a failed write: the file as far as its last complete record, then DataEnd and
        a Footer (no summary). OSError if even that cannot be written."""
        if self.ended:
            return
        self.ended = True
        self._drop_reserve()
        self._f.truncate(self.good)
        self._f.seek(self.good)
        tail = RecordBuilder()
        DataEnd(data_section_crc=0).write(tail)  # 0: no CRC (the data section was cut)
        Footer(summary_start=0, summary_offset_start=0, summary_crc=0).write(tail)
        self.write(tail.end() + MCAP0_MAGIC)
        self._f.close()

    def close(self, discard: bool = False) -> None:
        """Close; discard: remove the file too (still claimed, so that it is this run's file)."""
        if not self._f.closed:
            self._f.close()
        self._drop_reserve()
        if discard:
            os.remove(self.path)
        self.claim.release()


def readable_extent(path: str) -> str:
    """What a reader gets from a recording ended after a failed write: 'N messages up to
    t = X s' (read with the mcap library, as any user's tool would)."""
    from mcap.reader import make_reader
    count, last = 0, 0
    try:
        with open(path, "rb") as f:
            for _, _, message in make_reader(f).iter_messages(log_time_order=False):
                count += 1
                last = max(last, message.log_time)
    except Exception as exc:  # noqa: BLE001 - the answer, reported: on damaged files the mcap reader
        # raises McapError, lz4's RuntimeError, KeyError, OverflowError, MemoryError, OSError, struct.error,
        # UnicodeDecodeError (measured on cut and corrupted copies)
        return f"{count} messages readable, then: {type(exc).__name__}: {exc}"
    return f"{count} messages up to t = {last * 1e-9:.2f} s"


def _stamp_layout(msg_class) -> Optional[str]:
    """Where a message's simulation time stamp is: "header" (first field a std_msgs/Header),
    "sequence" (first field a sequence of messages that start with one), or None."""
    try:
        first = next(iter(msg_class.get_fields_and_field_types().values()))
    except (AttributeError, StopIteration):
        return None
    if first == "std_msgs/Header":
        return "header"
    if first.startswith("sequence<") and first[9:-1] in ("geometry_msgs/TransformStamped",
                                                         "visualization_msgs/Marker"):
        return "sequence"
    return None


def _first_stamp(data: bytes, layout: Optional[str]) -> Optional[int]:
    """The stamp (ns) at the start of a CDR message of that layout; None if there is none."""
    offset = {"header": 4, "sequence": 8}.get(layout)
    if offset is None or len(data) < offset + 8 or (layout == "sequence" and data[4:8] == b"\0\0\0\0"):
        return None
    sec, nanosec = struct.unpack_from("<iI" if data[1] == 1 else ">iI", data, offset)
    return sec * 1_000_000_000 + nanosec


def type_name(msg_class) -> str:
    module = msg_class.__module__.split(".")[0]
    return f"{module}/msg/{msg_class.__name__}"


DRAIN_MAX = 1000  # messages of one topic taken per executor round beyond the first


class McapRecorder(Node):
    """Subscribes the given topics (raw CDR) and writes them to an MCAP file."""

    def __init__(self, path: str, topics: List[Tuple[str, type, QoSProfile]], period_ns: Optional[int] = None,
                 fed_topics: Tuple[str, ...] = (), metadata: Optional[Dict[str, Dict[str, str]]] = None,
                 by_stamp: Tuple[str, ...] = (), claim: Optional[OutputClaim] = None):
        """claim: the path's OutputClaim, taken by the caller before anything started (else taken
        here; RecordingInUse if another run holds it). fed_topics: not subscribed; recorded from record() calls of their owner in this
        process (the scenario runner's /clock and /sim/step, and /sim/step_done which it takes
        raw anyway) or from the nodes' feeds (add_pipe_feed, feed_in_process); a feed's message
        on any other topic is not recorded (that topic is subscribed). metadata: MCAP
        metadata records (name -> string map) written at the start, so a run that is cut
        short keeps them. by_stamp: subscribed topics whose messages are logged at their own
        stamp (the header's, or the first element's for a sequence of stamped messages such as
        /tf and markers) instead of the time of arrival; latest_stamp holds the newest."""
        super().__init__("recorder")
        self.path = path
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        self._file = RecordingFile(path, claim)
        self.failure: Optional[OSError] = None  # the write that failed; the file was then ended readably
        # LZ4: a quarter of zstd's CPU per chunk here, and every MCAP reader supports it.
        self.writer = Writer(self._file, compression=CompressionType.LZ4)
        self.writer.start(profile="ros2", library="tugsim-recorder")
        for name, record in (metadata or {}).items():
            self.writer.add_metadata(name, dict(record))
        self.schemas: Dict[str, int] = {}
        self.channels: Dict[str, int] = {}
        self.counts: Dict[str, int] = {}  # topic -> messages taken (queued or written)
        self.topic_info: Dict[str, dict] = {}  # topic -> rosbag2 topic metadata, "count" = messages written
        self.time_range: Optional[Tuple[int, int]] = None  # log times of the first and last message written
        self.subscriptions_by_topic = {}
        self.sequence = 0
        # Simulation time of what is arriving, set by the conductor (orders and the trigger of
        # step k at k*T, the outputs of step k+1 at (k+1)*T); never goes backwards.
        self.log_time_ns = 0
        self.closed = False
        self.taps: Dict[str, Callable[[bytes], None]] = {}
        self._pending: List[Tuple[str, int, int, bytes]] = []
        self.fed_topics = set(fed_topics)
        self.pipes: List[PipeReader] = []
        self.refused: Dict[str, int] = {}  # topic -> undecodable messages not recorded
        self.complaints = RateLimitedLog(self.get_logger())
        self.by_stamp = {t: _stamp_layout(c) for t, c, _qos in topics if t in set(by_stamp)}
        self.latest_stamp: Dict[str, int] = {}  # by_stamp topic -> newest stamp recorded
        for topic, msg_class, qos in topics:
            self.add_topic(topic, msg_class, qos)

    def add_topic(self, topic: str, msg_class, qos: QoSProfile) -> None:
        tname = type_name(msg_class)
        if tname not in self.schemas:
            self.schemas[tname] = self.writer.register_schema(
                name=tname, encoding="ros2msg", data=message_definition(tname).encode())
        thash = type_hash(tname)
        if not thash:
            self.get_logger().warning(f"{topic}: no type description (share/{tname.split('/')[0]}/msg/"
                                      f"{tname.split('/')[-1]}.json) for {tname}: recorded without its type hash")
        self.channels[topic] = self.writer.register_channel(
            topic=topic, message_encoding="cdr", schema_id=self.schemas[tname],
            metadata={"offered_qos_profiles": qos_yaml(qos), "topic_type_hash": thash})
        self.counts[topic] = 0
        self.topic_info[topic] = {"name": topic, "type": tname, "qos": [qos_dict(qos)], "hash": thash, "count": 0}
        if topic in self.fed_topics:
            return
        # KEEP_ALL on the reader side so no message is dropped while the writer is busy.
        reader_qos = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=qos.reliability,
                                durability=qos.durability)
        self.subscriptions_by_topic[topic] = self.create_subscription(
            msg_class, topic, lambda data, t=topic, c=msg_class: self._take(t, c, data), reader_qos, raw=True)

    def tap(self, topic: str, callback: Callable[[bytes], None]) -> bool:
        """Hand every recorded message of topic (serialized) to callback as well; False if the
        topic is not recorded."""
        if topic not in self.channels:
            return False
        self.taps[topic] = callback
        return True

    def unmatched_topics(self) -> List[str]:
        """Topics where the graph has more publishers than this recorder has matched yet."""
        return [t for t, sub in self.subscriptions_by_topic.items()
                if sub.get_publisher_count() < self.count_publishers(t)]

    def record(self, topic: str, data: bytes) -> None:
        """Record a serialized message of a fed topic (published by this process)."""
        self._write(topic, data)

    def add_pipe_feed(self, fd: int) -> None:
        """Record what a node process writes into this pipe (read end; the recorder closes it)."""
        self.pipes.append(PipeReader(fd))

    def feed_in_process(self, topic: str, log_time_ns: int, data: bytes) -> None:
        """The feed of nodes running in this process (record_feed.install). Only fed topics: a
        topic also published by a node the runner did not start (/tf) is subscribed instead."""
        if topic in self.fed_topics and topic in self.channels:
            self._queue(topic, log_time_ns, data)

    def _write(self, topic: str, data: bytes) -> None:
        layout = self.by_stamp.get(topic)
        if layout is None:
            return self._queue(topic, self.log_time_ns, data)
        stamp = _first_stamp(data, layout)
        if stamp is None:
            return self._queue(topic, self.log_time_ns, data)
        if stamp > self.latest_stamp.get(topic, -1):
            self.latest_stamp[topic] = stamp
        self._queue(topic, stamp, data)

    def lagging(self, stamp_ns: int, topics) -> List[str]:
        """Of these by_stamp topics, those with no message stamped stamp_ns or later yet."""
        return [t for t in topics if self.latest_stamp.get(t, -1) < stamp_ns]

    def _take(self, topic: str, msg_class, data: bytes) -> None:
        """The message the executor hands over, then what else the topic's reader holds (up to
        DRAIN_MAX): a burst costs the runner one executor round instead of one per message
        (measured: rclpy rebuilds its wait set every round, and a 20,000-message command flood
        made 14 of 600 paced steps overrun)."""
        self._write_checked(topic, msg_class, data)
        sub = self.subscriptions_by_topic[topic]
        with sub.handle:
            for _ in range(DRAIN_MAX):
                taken = sub.handle.take_message(msg_class, True)
                if taken is None:
                    break
                self._write_checked(topic, msg_class, taken[0])

    def _write_checked(self, topic: str, msg_class, data: bytes) -> None:
        """Messages from anybody on the domain: bytes that are not a message of the topic's type
        are refused (logged, counted in self.refused), so every reader can decode the file."""
        try:
            deserialize_message(data, msg_class)
        except ros_decode_errors() as exc:
            self.refused[topic] = self.refused.get(topic, 0) + 1
            self.complaints("undecodable " + topic, f"{topic}: {len(data)} bytes that are not a "
                            f"{msg_class.__name__} not recorded: {exc}")
            return
        self._write(topic, data)

    def _queue(self, topic: str, log_time_ns: int, data: bytes) -> None:
        # Only queued here: the owner calls flush() when it has time (the scenario runner
        # while the nodes compute the next step), so writing is off the step's critical path.
        if self.closed:
            return
        self._pending.append((topic, log_time_ns, self.sequence, data))
        self.sequence += 1
        self.counts[topic] += 1

    def flush(self) -> None:
        """Write the queued messages and what the pipes hold (and hand them to the taps). A
        failed write (disk full) ends the file readably and raises the OSError."""
        try:
            self._flush()
        except OSError as exc:
            self._fail(exc)
            raise

    def _fail(self, exc: OSError) -> None:
        if self.failure is None:
            self.failure = exc
            self.closed = True
            try:
                self._file.end_readably()
            except OSError as again:
                self.get_logger().error(f"{self.path}: could not end the file after '{exc}': {again}")

    def _flush(self) -> None:
        for pipe in self.pipes:
            for topic, log_time, data in pipe.read():
                self.feed_in_process(topic, log_time, data)
        pending, self._pending = self._pending, []
        # A pipe may already hold outputs of the step now being computed: sorting each batch by
        # log time (stable) keeps the file in time order.
        pending.sort(key=lambda m: m[1])
        for topic, log_time, sequence, data in pending:
            self.writer.add_message(channel_id=self.channels[topic], log_time=log_time, data=data,
                                    publish_time=log_time, sequence=sequence)
            self.topic_info[topic]["count"] += 1
            first, last = self.time_range or (log_time, log_time)
            self.time_range = (min(first, log_time), max(last, log_time))
            tap = self.taps.get(topic)
            if tap is not None:
                tap(data)

    def close(self, discard: bool = False) -> None:
        """Write what is queued, the rosbag2 metadata and the summary. OSError if writing fails
        (the file is then ended readably, as in flush). discard: then remove the file (a run
        refused before its first step: start-up messages would pass for a recording)."""
        try:
            if not self.closed:  # else: closed already, or ended after a failed write
                self._flush()
                self.closed = True
                self.writer.add_metadata("rosbag2", {"serialized_metadata": self.serialized_metadata()})
                self.writer.finish()
        except OSError as exc:
            self._fail(exc)
            raise
        finally:
            for pipe in self.pipes:
                pipe.close()
            self._file.close(discard)

    def serialized_metadata(self) -> str:
        """rosbag2's BagMetadata YAML of what has been written so far."""
        first, last = self.time_range or (None, None)
        return to_yaml(bag_metadata(os.path.basename(self.path), list(self.topic_info.values()), first, last))
