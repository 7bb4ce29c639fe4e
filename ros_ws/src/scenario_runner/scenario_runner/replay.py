"""Replay an MCAP recording on its original topics, with its original timing and /clock.

    ros2 run scenario_runner replay output/default_demo.mcap [--rate 2] [--start-offset 30] [--loop]
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
from typing import Callable, Dict, List, Optional

from scenario_runner.mcap_io import Channel, McapFile, McapReadError, locate_recording, message_class

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
    """The publisher QoS for a channel: from its offered_qos_profiles (rosbag2 YAML, one entry
    per original publisher). Several publishers: reliable / transient local only if all offered
    it, the largest depth. Missing or unreadable metadata: reliable, volatile, keep last 10
    (transient local for /tf_static)."""
    import yaml
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    profiles = []
    text = channel.metadata.get("offered_qos_profiles", "")
    if text.strip():
        try:
            data = yaml.safe_load(text)
            profiles = [p for p in (data if isinstance(data, list) else [data]) if isinstance(p, dict)]
        except yaml.YAMLError:
            profiles = []
    if not profiles:
        tl = channel.topic == "/tf_static"
        return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100 if tl else 10,
                          reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL if tl else DurabilityPolicy.VOLATILE), False
    rel = [_policy(p.get("reliability"), _RELIABILITY) for p in profiles]
    dur = [_policy(p.get("durability"), _DURABILITY) for p in profiles]
    hist = [_policy(p.get("history"), _HISTORY) for p in profiles]
    depths = [int(p.get("depth") or 0) for p in profiles if str(p.get("depth", "")).strip().isdigit()]
    reliability = ReliabilityPolicy.BEST_EFFORT if any(r == 2 for r in rel) else ReliabilityPolicy.RELIABLE
    durability = DurabilityPolicy.TRANSIENT_LOCAL if all(d == 1 for d in dur) else DurabilityPolicy.VOLATILE
    depth = max(depths) if depths and max(depths) > 0 else 10
    if all(h == 2 for h in hist):
        return QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=reliability, durability=durability), True
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=reliability,
                      durability=durability), True


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
    if not args.rate > 0:
        sys.stderr.write("replay: --rate must be > 0\n")
        return EXIT_NOTHING
    try:
        keep = topic_filter(args.topics, args.exclude)
    except ValueError as exc:
        sys.stderr.write(f"replay: {exc}\n")
        return EXIT_NOTHING

    # -- first pass: channels, counts, problems --------------------------------------------
    try:
        path, note = locate_recording(args.recording)  # a rosbag2 directory: its .mcap; sqlite3: what to do
        if note:
            _print(args.quiet, f"replay: {note}")
        args.recording = path
        mf = McapFile(path).scan()
    except McapReadError as exc:
        sys.stderr.write(f"replay: {exc}\n")
        return EXIT_NOTHING
    if mf.problems:
        sys.stderr.write(f"replay: the recording is damaged; replaying its readable part:\n{mf.report()}\n")
    if mf.message_count == 0:
        sys.stderr.write(f"replay: {args.recording}: no readable message, nothing to replay\n")
        return EXIT_NOTHING

    # -- publishers ------------------------------------------------------------------------
    selected: Dict[str, Channel] = {}
    skipped: List[str] = []
    for topic, ch in sorted(mf.topics().items()):
        if not keep(topic) or not any(mf.counts.get(c.id) for c in mf.channels.values() if c.topic == topic):
            continue
        if topic == CLOCK_TOPIC and args.clock != "recorded":
            skipped.append(f"{topic}: recorded /clock not played (--clock {args.clock})")
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
    if args.list:
        for topic, ch in sorted(mf.topics().items()):
            n = sum(mf.counts.get(c.id, 0) for c in mf.channels.values() if c.topic == topic)
            q, known = qos_from_metadata(ch)
            mark = "" if topic in selected else "  (not played)"
            print(f"{topic}  {ch.type_name}  {n} msgs  QoS {qos_text(q)}{'' if known else ' (default)'}{mark}")
        for line in skipped:
            print(f"  {line}")
        return EXIT_DAMAGED if mf.problems else EXIT_OK
    for line in skipped:
        sys.stderr.write(f"replay: {line}\n")
    if not selected:
        sys.stderr.write(f"replay: {args.recording}: no topic left to play (selection, types)\n")
        return EXIT_NOTHING

    import rclpy.duration
    import rclpy.executors
    from rclpy.signals import SignalHandlerOptions
    # Ctrl-C / SIGTERM stop the playing loop as KeyboardInterrupt (then a clean shutdown)
    rclpy.init(args=["replay"] + argv, signal_handler_options=SignalHandlerOptions.NO)
    signal.signal(signal.SIGTERM, lambda *_: (_ for _ in ()).throw(KeyboardInterrupt()))
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rclpy.serialization import deserialize_message
    from rosgraph_msgs.msg import Clock
    node = Node("mcap_replay")
    pubs = {}
    classes = {}
    for topic, ch in selected.items():
        cls = message_class(ch.type_name)
        q, _ = qos_from_metadata(ch)
        classes[topic] = cls
        pubs[topic] = node.create_publisher(cls, topic, q)
    clock_pub = None
    if args.clock == "log":
        clock_ch = mf.topics().get(CLOCK_TOPIC)
        clock_qos = qos_from_metadata(clock_ch)[0] if clock_ch else QoSProfile(
            depth=10, reliability=ReliabilityPolicy.RELIABLE)
        clock_pub = node.create_publisher(Clock, CLOCK_TOPIC, clock_qos)

    def clock_msg(ns: int) -> Clock:
        c = Clock()
        c.clock.sec, c.clock.nanosec = ns // 1_000_000_000, ns % 1_000_000_000
        return c

    status = EXIT_DAMAGED if mf.problems else EXIT_OK
    sent = 0
    dropped_suspect = 0
    lateness: List[float] = []  # s after its due wall time each message went out
    try:
        all_pubs = list(pubs.values()) + ([clock_pub] if clock_pub else [])
        if args.wait_for_subscribers > 0:
            deadline = time.monotonic() + args.wait_for_subscribers
            while time.monotonic() < deadline and any(p.get_subscription_count() == 0 for p in all_pubs):
                time.sleep(0.02)
            lonely = [p.topic_name for p in all_pubs if p.get_subscription_count() == 0]
            if lonely:
                _print(args.quiet, f"replay: no subscriber yet on {len(lonely)} topic(s) after "
                                   f"{args.wait_for_subscribers:g} s; playing anyway")
        if args.delay > 0:
            time.sleep(args.delay)
        first = mf.start_time or 0
        log0 = first + int(round(args.start_offset * 1e9))
        log_end = log0 + int(round(args.duration * 1e9)) if args.duration is not None else None
        _print(args.quiet, f"replay: {args.recording}: {len(pubs)} topic(s), log time "
                           f"{log0 * 1e-9:.3f} .. {((log_end if log_end is not None else mf.end_time) or 0) * 1e-9:.3f}"
                           f" s at rate {args.rate:g}{', looping' if args.loop else ''}")
        clock_period = 1.0 / args.clock_hz if clock_pub and args.clock_hz > 0 else None
        wanted = lambda t: t in pubs  # noqa: E731
        t_wall0 = time.monotonic()
        for loop in itertools.count():
            wall0 = time.monotonic()
            last_clock = -1
            next_tick = wall0
            for msg in mf.messages_in_time_order(wanted):
                if msg.log_time < log0:
                    continue
                if log_end is not None and msg.log_time > log_end:
                    break
                target = wall0 + (msg.log_time - log0) * 1e-9 / args.rate
                while True:
                    now = time.monotonic()
                    if now >= target:
                        break
                    if clock_period is not None and next_tick < target:
                        if now >= next_tick:
                            play_ns = log0 + int((now - wall0) * args.rate * 1e9)
                            if play_ns > last_clock:
                                clock_pub.publish(clock_msg(play_ns))
                                last_clock = play_ns
                            next_tick = now + clock_period
                        time.sleep(max(0.0, min(next_tick, target) - time.monotonic()))
                    else:
                        time.sleep(target - now)
                if clock_pub is not None and msg.log_time > last_clock:
                    clock_pub.publish(clock_msg(msg.log_time))
                    last_clock = msg.log_time
                    next_tick = time.monotonic() + (clock_period or 0.0)
                if msg.suspect:
                    try:  # from a chunk that failed its CRC: send only what still decodes
                        deserialize_message(msg.data, classes[msg.topic])
                    except Exception:  # noqa: BLE001
                        dropped_suspect += 1
                        continue
                pubs[msg.topic].publish(msg.data)
                lateness.append(time.monotonic() - target)
                sent += 1
            if not args.loop:
                break
            _print(args.quiet, f"replay: loop {loop + 1} done, starting again")
        for p in all_pubs:
            p.wait_for_all_acked(rclpy.duration.Duration(seconds=2.0))
        late = sorted(lateness) or [0.0]
        _print(args.quiet, f"replay: {sent} messages sent in {time.monotonic() - t_wall0:.1f} s wall; sent after "
                           f"their due time by p50 {1e3 * late[len(late) // 2]:.1f} ms, p95 "
                           f"{1e3 * late[int(0.95 * (len(late) - 1))]:.1f} ms, max {1e3 * late[-1]:.1f} ms"
                           + (f"; {dropped_suspect} corrupt messages not sent" if dropped_suspect else ""))
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        _print(args.quiet, f"replay: stopped after {sent} messages")
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    if mf.problems:
        sys.stderr.write(f"replay: {args.recording}: damaged file, its readable part was replayed "
                         f"({len(mf.problems)} problem(s) above)\n")
    return status


if __name__ == "__main__":
    sys.exit(main())
