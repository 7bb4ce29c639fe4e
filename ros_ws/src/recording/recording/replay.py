"""Replay an MCAP recording on its original topics, with its original timing and /clock.

    ros2 run recording replay output/default_demo.mcap [--rate 2] [--start-offset 30] [--loop]
        [--topics '/tug/.*' /towline/state] [--exclude '.*/markers'] [--clock log|recorded|none]

Every message goes out as the serialized CDR bytes of the recording (no re-serialisation), on
a publisher of the recorded type (the type name in the file's own schema, e.g.
nav_msgs/msg/Odometry: it must be importable here) with the QoS the original publisher offered
(rosbag2's ``offered_qos_profiles`` channel metadata), so RViz, Foxglove or any node sees the
replay as live. Message i is sent at wall time start + (log_time_i - log_time_start) / rate;
/clock (rosgraph_msgs/Clock) carries the log time of the messages being sent, so nodes with
use_sim_time follow the recording. Works on this project's recordings and on rosbag2 MCAP
files of other ROS 2 tools. A truncated or corrupt file is reported (path, byte offset, what
is wrong) and its readable part is replayed.

Exit status: 0 done; 1 done, but the file is damaged (only its readable part was replayed);
2 nothing to replay (not an MCAP file, no readable message, no topic selected or importable).
"""
from __future__ import annotations

import argparse
import itertools
import re
import signal
import sys
import time
from typing import Callable, Dict, List, Optional, Tuple

from recording.mcap_io import (Channel, McapFile, McapReadError, locate_recording, message_class,
                                     ros_decode_errors)
from sim_plumbing.dds_profile import use_discovery_profile

CLOCK_TOPIC = "/clock"
EXIT_OK, EXIT_DAMAGED, EXIT_NOTHING = 0, 1, 2

_HISTORY = {"keep_last": 1, "keep_all": 2, "system_default": 0, "unknown": 3}
_RELIABILITY = {"reliable": 1, "best_effort": 2, "system_default": 0, "unknown": 3, "best_available": 4}
_DURABILITY = {"transient_local": 1, "volatile": 2, "system_default": 0, "unknown": 3, "best_available": 4}


def _policy(value, names: Dict[str, int]) -> Optional[int]:
    """rosbag2 writes policies as integers (Humble, this project) or names (Jazzy)."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int):
        return value
    if isinstance(value, str):
        v = value.strip().lower()
        if v.isdigit():
            return int(v)
        return names.get(v)
    return None


def qos_from_metadata(channel: Channel):
    """(QoS, fallback) of the publisher for a channel: from its offered_qos_profiles (rosbag2 YAML,
    one entry per original publisher); fallback is '' then, else why the default was taken.
    Several publishers: reliable / transient local only if all offered it, the largest depth.
    Missing or unreadable metadata: reliable, volatile, keep last 10 (transient local for
    /tf_static). A policy value not understood counts as the default (reliable, volatile, keep
    last) and is named in fallback."""
    import yaml
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    profiles, why = [], ""
    text = channel.metadata.get("offered_qos_profiles", "")
    if not text.strip():
        why = "the recording holds no offered_qos_profiles for it"
    else:
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            why = f"its offered_qos_profiles is not valid YAML ({str(exc).splitlines()[0]})"
        else:
            profiles = [p for p in (data if isinstance(data, list) else [data]) if isinstance(p, dict)]
            why = "" if profiles else "its offered_qos_profiles holds no QoS profile"
    if not profiles:
        tl = channel.topic == "/tf_static"
        return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100 if tl else 10,
                          reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL if tl else DurabilityPolicy.VOLATILE), why
    rel = [_policy(p.get("reliability"), _RELIABILITY) for p in profiles]
    dur = [_policy(p.get("durability"), _DURABILITY) for p in profiles]
    hist = [_policy(p.get("history"), _HISTORY) for p in profiles]
    depths = [int(p.get("depth") or 0) for p in profiles if str(p.get("depth", "")).strip().isdigit()]
    reliability = ReliabilityPolicy.BEST_EFFORT if any(r == 2 for r in rel) else ReliabilityPolicy.RELIABLE
    durability = DurabilityPolicy.TRANSIENT_LOCAL if all(d == 1 for d in dur) else DurabilityPolicy.VOLATILE
    depth = max(depths) if depths and max(depths) > 0 else 10
    tables = {"reliability": _RELIABILITY, "durability": _DURABILITY, "history": _HISTORY}
    unread = [f"{key} {p[key]!r}" for p in profiles for key, names in tables.items()
              if p.get(key) is not None and _policy(p[key], names) is None]
    why = f"offered_qos_profiles: {', '.join(unread)} not understood" if unread else ""
    if all(h == 2 for h in hist):
        return QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=reliability, durability=durability), why
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=reliability,
                      durability=durability), why


def qos_text(q) -> str:
    hist = "keep all" if int(q.history) == 2 else f"keep last {q.depth}"
    rel = "reliable" if int(q.reliability) == 1 else "best effort"
    dur = "transient local" if int(q.durability) == 1 else "volatile"
    return f"{rel}, {dur}, {hist}"


def topic_filter(include: Optional[List[str]], exclude: Optional[List[str]]) -> Callable[[str], bool]:
    """Each item is a topic name or a regular expression (full match); items may also be
    comma-separated. No include list: every topic."""
    def compile_all(items):
        out = []
        for item in items or []:
            for part in item.split(","):
                part = part.strip()
                if part:
                    try:
                        out.append(re.compile(part))
                    except re.error as exc:
                        raise ValueError(f"bad topic pattern {part!r}: {exc}") from None
        return out
    inc, exc = compile_all(include), compile_all(exclude)

    def keep(topic: str) -> bool:
        if inc and not any(p.fullmatch(topic) for p in inc):
            return False
        return not any(p.fullmatch(topic) for p in exc)
    return keep


def _print(quiet: bool, text: str) -> None:
    if not quiet:
        print(text, flush=True)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="replay", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Exit status: 0 done; 1 damaged file, its readable part replayed; "
                                       "2 nothing to replay.")
    p.add_argument("recording", help="MCAP file (this project's recorder or rosbag2's MCAP storage)")
    p.add_argument("--rate", type=float, default=1.0, help="playback speed factor (2 = twice as fast); default 1")
    p.add_argument("--start-offset", type=float, default=0.0, metavar="S",
                   help="start this many seconds (log time) after the recording's first message")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="play only this many seconds of log time from the start point")
    p.add_argument("--loop", action="store_true", help="start again from the start point at the end (Ctrl-C stops)")
    p.add_argument("--topics", nargs="+", metavar="TOPIC", help="play only these topics: names or regular "
                   "expressions (full match), space- or comma-separated; default: all")
    p.add_argument("--exclude", nargs="+", metavar="TOPIC", help="do not play these topics (names or regexes)")
    p.add_argument("--clock", choices=("log", "recorded", "none"), default="log",
                   help="/clock source: 'log' (default) publishes the log time of the messages being sent (the "
                        "recorded /clock topic is then not played), 'recorded' plays the recorded /clock messages "
                        "like any topic, 'none' publishes no /clock")
    p.add_argument("--clock-hz", type=float, default=20.0,
                   help="with --clock log, also publish /clock at this wall rate during gaps between messages "
                        "(0: only at message times); default 20")
    p.add_argument("--delay", type=float, default=0.5, metavar="S",
                   help="wait this long after creating the publishers (discovery) before playing; default 0.5")
    p.add_argument("--wait-for-subscribers", type=float, default=0.0, metavar="TIMEOUT",
                   help="before playing, wait up to TIMEOUT s until every publisher has a subscriber")
    p.add_argument("--list", action="store_true", help="only list the file's topics, types, counts and QoS")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    return p


def main(argv: Optional[List[str]] = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    import rclpy
    args = build_parser().parse_args(rclpy.utilities.remove_ros_args(["replay"] + argv)[1:])
    keep = check_options(args)
    if keep is None:
        return EXIT_NOTHING
    mf = open_recording(args)
    if mf is None:
        return EXIT_NOTHING
    selected, skipped = select_topics(mf, keep, args.clock)
    if args.list:
        list_topics(mf, selected, skipped)
        return EXIT_DAMAGED if mf.problems else EXIT_OK
    for line in skipped:
        sys.stderr.write(f"replay: {line}\n")
    if not selected:
        sys.stderr.write(f"replay: {args.recording}: no topic left to play (selection, types)\n")
        return EXIT_NOTHING
    play(args, argv, mf, selected)
    if mf.problems:
        sys.stderr.write(f"replay: {args.recording}: damaged file, its readable part was replayed "
                         f"({len(mf.problems)} problem(s) above)\n")
        return EXIT_DAMAGED
    return EXIT_OK


def check_options(args) -> Optional[Callable[[str], bool]]:
    """The topic filter of --topics / --exclude; None (said on stderr) for unusable options."""
    if not args.rate > 0:
        sys.stderr.write("replay: --rate must be > 0\n")
        return None
    try:
        return topic_filter(args.topics, args.exclude)
    except ValueError as exc:
        sys.stderr.write(f"replay: {exc}\n")
        return None


def open_recording(args) -> Optional[McapFile]:
    """The recording scanned once (channels, counts, problems; damage reported on stderr), or
    None (said on stderr) if there is nothing to replay. args.recording becomes the MCAP file."""
    try:
        path, note = locate_recording(args.recording)  # a rosbag2 directory: its .mcap; sqlite3: what to do
        if note:
            _print(args.quiet, f"replay: {note}")
        args.recording = path
        mf = McapFile(path).scan()
    except McapReadError as exc:
        sys.stderr.write(f"replay: {exc}\n")
        return None
    if mf.problems:
        sys.stderr.write(f"replay: the recording is damaged; replaying its readable part:\n{mf.report()}\n")
    if mf.message_count == 0:
        sys.stderr.write(f"replay: {args.recording}: no readable message, nothing to replay\n")
        return None
    return mf


def select_topics(mf: McapFile, keep: Callable[[str], bool], clock: str) -> Tuple[Dict[str, Channel], List[str]]:
    """(topic -> channel to play, why each other topic with messages is not played)."""
    selected: Dict[str, Channel] = {}
    skipped: List[str] = []
    for topic, ch in sorted(mf.topics().items()):
        if not keep(topic) or not any(mf.counts.get(c.id) for c in mf.channels.values() if c.topic == topic):
            continue
        if topic == CLOCK_TOPIC and clock != "recorded":
            skipped.append(f"{topic}: recorded /clock not played (--clock {clock})")
            continue
        if ch.message_encoding != "cdr":
            skipped.append(f"{topic}: message encoding {ch.message_encoding!r} is not ROS 2 CDR; skipped")
            continue
        try:
            message_class(ch.type_name)
        except (ImportError, ValueError) as exc:
            skipped.append(f"{topic}: {exc}; skipped")
            continue
        selected[topic] = ch
    return selected, skipped


def list_topics(mf: McapFile, selected: Dict[str, Channel], skipped: List[str]) -> None:
    """--list: every topic with its type, message count and the QoS it would be played with."""
    for topic, ch in sorted(mf.topics().items()):
        n = sum(mf.counts.get(c.id, 0) for c in mf.channels.values() if c.topic == topic)
        q, fallback = qos_from_metadata(ch)
        mark = "" if topic in selected else "  (not played)"
        print(f"{topic}  {ch.type_name}  {n} msgs  QoS {qos_text(q)}{f' (default: {fallback})' if fallback else ''}"
              f"{mark}")
    for line in skipped:
        print(f"  {line}")


def play(args, argv: List[str], mf: McapFile, selected: Dict[str, Channel]) -> None:
    """Publish the selected topics (and /clock) at their recorded times until the end, or until
    Ctrl-C / SIGTERM."""
    import rclpy
    import rclpy.executors
    from rclpy.signals import SignalHandlerOptions
    # Ctrl-C / SIGTERM stop the playing loop as KeyboardInterrupt (then a clean shutdown)
    use_discovery_profile()
    rclpy.init(args=["replay"] + argv, signal_handler_options=SignalHandlerOptions.NO)
    signal.signal(signal.SIGINT, signal.default_int_handler)  # also when started with SIGINT ignored
    signal.signal(signal.SIGTERM, lambda *_: (_ for _ in ()).throw(KeyboardInterrupt()))
    from rclpy.node import Node
    node = Node("mcap_replay")
    player = Player(args, mf, node, selected)
    try:
        player.wait_for_subscribers()
        player.play()
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        _print(args.quiet, f"replay: stopped after {player.sent} messages")
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


class Player:
    """The publishers of a replay and its playing loop: message i goes out at wall time
    start + (log_time_i - log0) / rate, /clock at message times and between them."""

    def __init__(self, args, mf: McapFile, node, selected: Dict[str, Channel]):
        self.args, self.mf = args, mf
        self.pubs, self.classes = {}, {}
        for topic, ch in selected.items():
            cls = message_class(ch.type_name)
            q, fallback = qos_from_metadata(ch)
            if fallback:
                sys.stderr.write(f"replay: {topic}: {fallback}; publishing it with the default QoS ({qos_text(q)})\n")
            self.classes[topic] = cls
            self.pubs[topic] = node.create_publisher(cls, topic, q)
        self.clock_pub = self._clock_publisher(node) if args.clock == "log" else None
        self.all_pubs = list(self.pubs.values()) + ([self.clock_pub] if self.clock_pub else [])
        self.sent = 0
        self.undecodable: Dict[str, int] = {}  # topic -> suspect messages not sent
        self.lateness: List[float] = []  # s after its due wall time each message went out

    def _clock_publisher(self, node):
        """/clock from the log times, with the recorded /clock's QoS (reliable, keep last 10 if none)."""
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from rosgraph_msgs.msg import Clock
        clock_ch = self.mf.topics().get(CLOCK_TOPIC)
        if clock_ch is None:
            clock_qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        else:
            clock_qos, fallback = qos_from_metadata(clock_ch)
            if fallback:
                sys.stderr.write(f"replay: {CLOCK_TOPIC}: {fallback}; publishing it with the default QoS "
                                 f"({qos_text(clock_qos)})\n")
        self._clock_type = Clock
        return node.create_publisher(Clock, CLOCK_TOPIC, clock_qos)

    def wait_for_subscribers(self) -> None:
        """--wait-for-subscribers, then --delay (discovery)."""
        args = self.args
        if args.wait_for_subscribers > 0:
            deadline = time.monotonic() + args.wait_for_subscribers
            while time.monotonic() < deadline and any(p.get_subscription_count() == 0 for p in self.all_pubs):
                time.sleep(0.02)
            lonely = [p.topic_name for p in self.all_pubs if p.get_subscription_count() == 0]
            if lonely:
                _print(args.quiet, f"replay: no subscriber yet on {len(lonely)} topic(s) after "
                                   f"{args.wait_for_subscribers:g} s; playing anyway")
        if args.delay > 0:
            time.sleep(args.delay)

    def play(self) -> None:
        """Every pass (one, or until stopped with --loop), then wait for the subscribers'
        acknowledgements and report."""
        import rclpy.duration
        args, mf = self.args, self.mf
        log0 = (mf.start_time or 0) + int(round(args.start_offset * 1e9))
        log_end = log0 + int(round(args.duration * 1e9)) if args.duration is not None else None
        _print(args.quiet, f"replay: {args.recording}: {len(self.pubs)} topic(s), log time "
                           f"{log0 * 1e-9:.3f} .. {((log_end if log_end is not None else mf.end_time) or 0) * 1e-9:.3f}"
                           f" s at rate {args.rate:g}{', looping' if args.loop else ''}")
        t_wall0 = time.monotonic()
        for loop in itertools.count():
            self.play_pass(log0, log_end)
            if not args.loop:
                break
            _print(args.quiet, f"replay: loop {loop + 1} done, starting again")
        for p in self.all_pubs:
            p.wait_for_all_acked(rclpy.duration.Duration(seconds=2.0))
        self.report(time.monotonic() - t_wall0)

    def play_pass(self, log0: int, log_end: Optional[int]) -> None:
        """One pass over the messages logged in [log0, log_end]."""
        from rclpy.serialization import deserialize_message
        rate = self.args.rate
        clock_period = 1.0 / self.args.clock_hz if self.clock_pub and self.args.clock_hz > 0 else None
        corrupt = ros_decode_errors()
        msgs = self.mf.messages_in_time_order(lambda t: t in self.pubs)
        # The first message comes only once the time-order window is filled (a whole file of up
        # to 200 000 messages read and decompressed: 70 ms for the 6 s demo, more on a loaded
        # host): the paced clock starts after it, or the recording's start goes out late in a burst.
        first = next((m for m in msgs if m.log_time >= log0), None)
        wall0 = time.monotonic()
        self._last_clock = -1
        self._next_tick = wall0
        for msg in itertools.chain([first] if first is not None else [], msgs):
            if msg.log_time < log0:
                continue
            if log_end is not None and msg.log_time > log_end:
                break
            target = wall0 + (msg.log_time - log0) * 1e-9 / rate
            self._wait_until(target, wall0, log0, clock_period)
            if self.clock_pub is not None and msg.log_time > self._last_clock:
                self._publish_clock(msg.log_time)
                self._next_tick = time.monotonic() + (clock_period or 0.0)
            if msg.suspect:
                try:  # from a chunk that failed its CRC: send only what still decodes
                    deserialize_message(msg.data, self.classes[msg.topic])
                except corrupt:
                    self.undecodable[msg.topic] = self.undecodable.get(msg.topic, 0) + 1
                    continue
            self.pubs[msg.topic].publish(msg.data)
            self.lateness.append(time.monotonic() - target)
            self.sent += 1

    def _wait_until(self, target: float, wall0: float, log0: int, clock_period: Optional[float]) -> None:
        """Sleep until wall time target, publishing /clock every clock_period meanwhile."""
        while True:
            now = time.monotonic()
            if now >= target:
                return
            if clock_period is not None and self._next_tick < target:
                if now >= self._next_tick:
                    play_ns = log0 + int((now - wall0) * self.args.rate * 1e9)
                    if play_ns > self._last_clock:
                        self._publish_clock(play_ns)
                    self._next_tick = now + clock_period
                time.sleep(max(0.0, min(self._next_tick, target) - time.monotonic()))
            else:
                time.sleep(target - now)

    def _publish_clock(self, ns: int) -> None:
        c = self._clock_type()
        c.clock.sec, c.clock.nanosec = ns // 1_000_000_000, ns % 1_000_000_000
        self.clock_pub.publish(c)
        self._last_clock = ns

    def report(self, wall: float) -> None:
        """How many messages went out and how late; the corrupt ones not sent, per topic (stderr)."""
        late = sorted(self.lateness) or [0.0]
        n_bad = sum(self.undecodable.values())
        _print(self.args.quiet, f"replay: {self.sent} messages sent in {wall:.1f} s wall; sent after "
                                f"their due time by p50 {1e3 * late[len(late) // 2]:.1f} ms, p95 "
                                f"{1e3 * late[int(0.95 * (len(late) - 1))]:.1f} ms, max {1e3 * late[-1]:.1f} ms"
                                + (f"; {n_bad} corrupt messages not sent" if n_bad else ""))
        for topic, n in sorted(self.undecodable.items()):
            sys.stderr.write(f"replay: {topic}: {n} message(s) from a chunk that failed its CRC do not decode as "
                             f"{self.classes[topic].__name__}; not sent\n")


if __name__ == "__main__":
    sys.exit(main())
