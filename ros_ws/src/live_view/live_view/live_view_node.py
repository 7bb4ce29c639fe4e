"""The live view: a Foxglove WebSocket server (foxglove-sdk) showing a running simulation.

    ros2 run live_view live_view                       # every topic on the graph, ws://127.0.0.1:8765
    ros2 run scenario_runner run_scenario default_demo.yaml --live

Every topic is served as a channel with message encoding ``cdr`` and a ``ros2msg`` schema (the
rosbag2 text of sim_plumbing.msg_definitions): the bytes the nodes publish go out unchanged,
so Foxglove and Lichtblick decode them as their own ROS 2 messages (3D scene from /tf,
/tf_static and the markers, plots, raw messages).

Cost (never holds up the lockstep): messages are only stored as they arrive (the newest per
topic; on /tf the newest per frame; every one of the rare order and event topics, bounded); a
sender thread (not the ROS executor, which in the runner's process is the lockstep's) sends what
is new at ``rate`` (default 20 Hz, wall clock) to subscribed clients: each message once into
foxglove-sdk, which frames it for each subscribed client in Rust; the WebSocket I/O runs in
foxglove-sdk's own threads; no Python work per client. On shutdown the node logs the sender's
achieved rate while the simulation ran, its CPU a round and the foxglove-sdk threads' CPU.
Started by ``run_scenario --live`` the node lives in the runner's process and takes the bytes
from the recorder as it writes them (no second DDS delivery of anything); started alone, it
subscribes the topics it serves (raw; the step protocol best-effort, so a slow viewer can never
make a keep-all writer wait).

Client input: only the vessels' ``command`` and the ropes' ``winch`` topics take client
messages (client_input.py: checked, clamped, written anew, stamped with the simulation time,
published); anything else a client advertises or sends is refused, logged (at most once a
second per kind) and counted, and so is input beyond ``input_rate`` orders a second per kind of
client and kind of order, all connections and addresses together (trust.SharedLimits). The
counts are in ``refused``, ``accepted`` and ``forwarded`` and in the log on shutdown.

Who may connect (trust.py, front.py; docs/live-view.md has the threat model): the WebSocket
server is reached through a front door that refuses a wrong Host (DNS rebinding) or Origin (a
page of another site; ``allowed_origins`` adds some) and more than ``max_clients`` connections;
foxglove-sdk's own server listens behind it on 127.0.0.1 with TLS, so a page cannot bypass it.

The time orders are stamped with: in the runner's process the run's own clock, handed over by
the runner (offer('/clock')); an order that passes the checks is "accepted". Stand-alone the
node follows /clock, which anyone on the domain may publish: a message that jumps ahead is not
followed (trust.ClockGuard, refused as "clock"), and since the node cannot tell whose clock it
follows, an order that passes the checks is "forwarded" (published; the vessel decides).

The node holds its servers in ``self.servers`` (each with a ``stop()``): the browser
instructor station (instructor.py: a page with a 3D view, gauges, a tension plot and controls,
on http://127.0.0.1:8080, parameter ``http_port``, -1 for none) is added with add_server() and
stopped with the node. Its commands go through the same checks, rate limit and counts as the
WebSocket clients' (take_input()). Every client's order is refused (counted as "ended") while
``orders_closed()`` gives a reason: the station's, during a replay and once the run or replay
has ended (nothing would obey it).
"""
from __future__ import annotations

import collections
import os
import ssl
import struct
import subprocess
import sys
import threading
import time
from typing import Callable, Deque, Dict, List, Optional, Sequence, Tuple

import rclpy
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from live_view import client_input, front, instructor, trust
from sim_contract.node_params import LIVE_VIEW
from sim_plumbing import cdr
from sim_plumbing import ros_common as rc
from sim_plumbing.msg_definitions import message_definition
from sim_plumbing.stepping import RateLimitedLog

STATIC_RESEND = 1.0  # s: latched topics (/tf_static) go out again so a client that joins late has them
MAX_QUEUED = 1000  # messages of an every-message topic held between two sends
MAX_CLIENT_CHANNELS = 64  # channels one client may advertise
PROTOCOL_TOPICS = (rc.SIM_STEP_TOPIC, rc.STEP_DONE_TOPIC)
_STAMP = struct.Struct("<iI")


def _import_type(full_type: str):
    import importlib
    pkg, sub, name = full_type.split("/")
    return getattr(importlib.import_module(f"{pkg}.{sub}"), name)


def _tf_key(data: bytes) -> Tuple[str, str]:
    """(parent, child) of the first transform of a tf2_msgs/TFMessage."""
    r = cdr.CdrReader(data)
    if r.uint32() == 0:
        return "", ""
    r.stamp_ns()
    return r.string(), r.string()


class TopicSlot:
    """What arrived on a topic since the last send. policy: latest (the newest message),
    keyed (the newest per key, /tf), static (the newest per key, re-sent every
    STATIC_RESEND s, /tf_static), every (each message, up to MAX_QUEUED)."""

    def __init__(self, topic: str, full_type: str, policy: str, channel):
        self.topic, self.full_type, self.policy, self.channel = topic, full_type, policy, channel
        self.latest: Optional[bytes] = None
        self.last: Optional[bytes] = None  # the newest message ever (never taken): the instructor station reads it
        self.keyed: Dict[object, bytes] = {}
        self.fresh: set = set()
        self.queue: Deque[bytes] = collections.deque(maxlen=MAX_QUEUED)
        self.dropped = 0
        self.received = 0
        self.sent = 0
        self.last_static = 0.0
        self.arrived = 0.0  # time.monotonic() of the newest message (the station's "no data for ... s")
        self.tap: Optional[Callable[[bytes], None]] = None  # every message, as it arrives (the station's events)
        self.lock = threading.Lock()

    def offer(self, data: bytes) -> None:
        self.received += 1
        self.last = data
        self.arrived = time.monotonic()
        if self.tap is not None:
            self.tap(data)
        if self.policy == "latest":
            with self.lock:
                self.latest = data
            return
        if self.policy == "every":
            if len(self.queue) == MAX_QUEUED:
                self.dropped += 1
            self.queue.append(data)
            return
        try:
            key = _tf_key(data)
        except cdr.CdrError:
            return
        with self.lock:
            self.keyed[key] = data
            self.fresh.add(key)

    def take(self, now: float) -> List[bytes]:
        """The messages to send now (called in the sender thread, offer() in the executor's)."""
        if self.policy == "latest":
            with self.lock:
                data, self.latest = self.latest, None
            return [data] if data is not None else []
        if self.policy == "every":
            out = []
            while self.queue:
                out.append(self.queue.popleft())
            return out
        with self.lock:
            if self.policy == "static" and now - self.last_static >= STATIC_RESEND:
                self.last_static = now
                self.fresh.clear()
                return list(self.keyed.values())
            out = [self.keyed[k] for k in self.fresh]
            self.fresh.clear()
            return out


def policy_of(topic: str, full_type: str) -> str:
    if topic == rc.TF_STATIC_TOPIC:
        return "static"
    if topic == rc.TF_TOPIC:
        return "keyed"
    if full_type in client_input.CHECKS or topic == rc.EVENTS_TOPIC:
        return "every"
    return "latest"


def subscription_qos(topic: str, transient_local: bool) -> QoSProfile:
    """A reader that can never make a writer wait: the keep-all step protocol best-effort;
    otherwise reliable keep-last (a keep-last writer overwrites rather than waits), transient-
    local where the publishers offer it (the step-0 state, /tf_static)."""
    if topic in PROTOCOL_TOPICS:
        return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.BEST_EFFORT,
                          durability=DurabilityPolicy.VOLATILE)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100 if topic.startswith("/tf") else 10,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if transient_local else DurabilityPolicy.VOLATILE)


class _Listener:
    """foxglove-sdk ServerListener: client channels and their messages (called in the server's
    threads)."""

    def __init__(self, node: "LiveViewNode"):
        self.node = node

    def on_client_advertise(self, client, channel) -> None:
        try:
            self.node.client_advertise(client.id, channel)
        except Exception as exc:  # noqa: BLE001 - nothing may escape into foxglove-sdk's thread
            self.node._refuse("error", f"client {client.id}: advertise: {type(exc).__name__}: {str(exc)[:200]}")

    def on_client_unadvertise(self, client, client_channel_id: int) -> None:
        self.node.client_channels.pop((client.id, client_channel_id), None)

    def on_message_data(self, client, client_channel_id: int, data: bytes) -> None:
        self.node.client_message(client.id, client_channel_id, data)

    def on_subscribe(self, client, channel) -> None:
        self.node.subscribed_once = True

    def on_unsubscribe(self, client, channel) -> None:
        pass


def thread_cpu_seconds(prefix: str) -> float:
    """CPU time (user + system, s) of this process's live threads whose name starts with prefix
    (foxglove-sdk's WebSocket I/O: 'tokio'); 0 where /proc is not there."""
    total = 0
    try:
        tasks = os.listdir("/proc/self/task")
    except OSError:
        return 0.0
    for tid in tasks:
        try:
            with open(f"/proc/self/task/{tid}/comm") as f:
                if not f.read().startswith(prefix):
                    continue
            with open(f"/proc/self/task/{tid}/stat") as f:
                fields = f.read().rpartition(")")[2].split()
            total += int(fields[11]) + int(fields[12])  # utime, stime (fields 14, 15 of stat)
        except (OSError, ValueError, IndexError):
            continue
    return total / os.sysconf("SC_CLK_TCK")


class Sender:
    """The thread that sends what is new at ``rate`` (wall clock), outside the ROS executor: in the
    runner's process the executor is the lockstep's, and a timer there runs inside a step's round
    trip and fires late whenever the steps keep the executor busy. A round missed (the process
    starved of CPU) is skipped, not caught up. It measures what it achieved while the simulation
    ran, from the first to the last round in which the simulation had advanced since the round
    before: its rounds a second and the longest interval between two rounds (summary())."""

    def __init__(self, send: Callable[[], bool], rate: float, on_error: Callable[[Exception], None]):
        self.send, self.period, self.on_error = send, 1.0 / rate, on_error
        self.rounds = 0
        self.cpu = 0.0  # s of this thread's CPU in send() (the per-client work of channel.log included)
        self.first_running: Optional[float] = None  # the first round after which the simulation had advanced
        self.running: Tuple[int, float, float] = (0, 0.0, 0.0)  # rounds, span, longest gap up to the last such round
        self._gap = 0.0
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self._loop, name="live-view-sender", daemon=True)
        self.thread.start()

    def _loop(self) -> None:
        next_t = time.monotonic() + self.period
        last = None
        while not self._stop.wait(max(0.0, next_t - time.monotonic())):
            c0 = time.thread_time()
            try:
                advanced = self.send()
            except Exception as exc:  # noqa: BLE001 - one bad round must not end the live view
                self.on_error(exc)
                advanced = False
            self.cpu += time.thread_time() - c0
            self.rounds += 1
            now = time.monotonic()
            if self.first_running is not None:
                self._gap = max(self._gap, now - last)
            if advanced:
                if self.first_running is None:
                    self.first_running, self._start_round = now, self.rounds
                self.running = (self.rounds - self._start_round, now - self.first_running, self._gap)
            last = now
            next_t += self.period
            if next_t < now:  # late: skip the missed rounds
                next_t = now + self.period

    def achieved_rate(self) -> Optional[float]:
        """Rounds a second while the simulation ran (None before it ran for two rounds)."""
        n, span, _ = self.running
        return n / span if n >= 1 and span > 0 else None

    def summary(self) -> str:
        rate = self.achieved_rate()
        if rate is None:
            return f"sender: {self.rounds} rounds, the simulation did not run"
        n, span, gap = self.running
        return (f"sender: {rate:.1f} Hz achieved while the simulation ran ({n + 1} rounds in {span:.1f} s, "
                f"longest gap {1000 * gap:.0f} ms, {1000 * self.cpu / max(1, self.rounds):.2f} ms CPU a round)")

    def stop(self) -> None:
        self._stop.set()
        self.thread.join(2.0)


class LiveViewNode(Node):
    """See the module docstring. topics: (topic, 'pkg/msg/Type', transient-local publishers?) to
    serve from the start;
    none (and discover:=true, the default alone): every topic on the graph of a known type,
    looked up every 2 s. offered_topics: topics someone in this process hands over with
    offer() (run_scenario --live: the recorder), not subscribed."""

    def __init__(self, node_name: str = "live_view", *, topics: Sequence[Tuple[str, str, bool]] = (),
                 offered_topics: Sequence[str] = (), **kwargs):
        super().__init__(node_name, **kwargs)
        rc.declare_table(self, LIVE_VIEW)
        rc.refuse_fixed_parameters(self, LIVE_VIEW)
        self.complaints = RateLimitedLog(self.get_logger())
        self.slots: Dict[str, TopicSlot] = {}
        self.offered = set(offered_topics)
        self.sim_time_ns = 0
        self._round_time = 0  # the simulation time of the sender's last round
        self.refused: collections.Counter = collections.Counter()  # why -> client messages refused
        self.accepted = 0  # orders stamped with the run's own clock (in the runner's process)
        self.forwarded = 0  # orders published with a clock the node cannot vouch for (stand-alone)
        self.clamped = 0
        self.client_channels: Dict[Tuple[int, int], Tuple[str, str, str]] = {}  # -> topic, type, encoding
        self._refused_channels: Dict[Tuple[int, int], str] = {}
        self.limits = trust.SharedLimits(lambda: self.get_parameter("input_rate").value)
        # the run's own clock is the one handed over in this process (the runner's); one taken from
        # the domain is guarded and never vouched for
        self.own_clock = "/clock" in self.offered
        self.clock_guard = trust.ClockGuard()
        self.order_time_ns = 0  # the time orders are stamped with (the guarded clock stand-alone)
        self.allowed_origins = trust.parse_origins(self.get_parameter("allowed_origins").value)
        self._input_pubs: Dict[str, object] = {}
        self._topic_types: Dict[str, str] = {}   # topic -> its type, set before its channel is advertised
        self.subscribed_once = False
        self.servers: List[object] = []
        self._taps: Dict[str, Callable[[bytes], None]] = {}
        # why orders go nowhere now (the run or replay has ended, a replay obeys none), else None:
        # set by the instructor station, asked for every client's order
        self.orders_closed: Callable[[], Optional[str]] = lambda: None

        import foxglove
        from foxglove.websocket import Capability
        self._foxglove = foxglove
        self.fg_context = foxglove.Context()
        for topic, full_type, latched in topics:
            self.add_topic(topic, full_type, latched)
        host = self.get_parameter("host").value
        # foxglove-sdk has no hook to check a connection's Origin / Host or count connections: its
        # server listens on 127.0.0.1 behind front.CheckedFront, with TLS whose certificate only the
        # front door trusts (a browser page that finds the port cannot connect). Without openssl
        # there is no certificate: clients may then only watch (no client publishing), said here.
        try:
            cert, key = front.make_certificate()
        except (OSError, subprocess.SubprocessError) as exc:
            cert = key = None
            self.get_logger().warning(f"no TLS certificate for the WebSocket server behind the front door ({exc}): "
                                      "clients may watch but not publish (is openssl installed?)")
        capabilities = [Capability.Time] + ([Capability.ClientPublish] if cert else [])
        self.client_publish = cert is not None
        self.server = foxglove.start_server(
            name="tugsim live view", host="127.0.0.1", port=0, capabilities=capabilities,
            supported_encodings=list(client_input.ENCODINGS), server_listener=_Listener(self),
            context=self.fg_context, tls_cert=cert, tls_key=key)
        self.add_server(self.server)
        backend_ssl = None
        if cert:
            backend_ssl = ssl.create_default_context(cadata=cert.decode())
            backend_ssl.check_hostname = False  # the one certificate trusted is this node's own
        ws_port = self.get_parameter("port").value
        http_port = self.get_parameter("http_port").value
        self.web_policy = trust.WebPolicy(host, [ws_port, http_port], self.allowed_origins)
        try:
            self.front = front.CheckedFront(host, ws_port, self.server.port, backend_ssl,
                                            self.get_parameter("max_clients").value, self.check_connection,
                                            self.refuse_connection)
        except OSError:
            self.server.stop()
            raise
        self.add_server(self.front)
        self.port = self.front.port
        self.sender = Sender(self.send, self.get_parameter("rate").value,
                             lambda exc: self.complaints("send", f"sending failed: {exc!r}", "warning"))
        if self.get_parameter("discover").value and not topics:
            self._discover_timer = self.create_timer(
                2.0, self.discover, clock=rclpy.clock.Clock(clock_type=rclpy.clock.ClockType.STEADY_TIME))
            self.discover()
        self.get_logger().info(f"live view on ws://{self.get_parameter('host').value}:{self.port} "
                               f"({len(self.slots)} topics, {self.get_parameter('rate').value:g} Hz)")
        self.station: Optional[instructor.InstructorStation] = None
        self.http_port: Optional[int] = None
        if self.get_parameter("http_port").value >= 0:
            try:
                self.station = instructor.InstructorStation(self)
            except OSError as exc:  # e.g. the port is taken: the live view goes on without the page
                self.get_logger().error(f"instructor station not started on {self.get_parameter('host').value}:"
                                        f"{self.get_parameter('http_port').value}: {exc}")
            else:
                self.add_server(self.station)
                self.http_port = self.station.port
        # the ports as bound (0: any free port): the Origins of this node's own pages
        self.web_policy = trust.WebPolicy(host, [self.port, self.http_port or 0], self.allowed_origins)

    # -- servers ---------------------------------------------------------------------------
    def tap(self, topic: str, callback: Callable[[bytes], None]) -> None:
        """Hand every message of topic (served now or later) to callback as it arrives (rare topics only:
        it runs in the receiving thread)."""
        self._taps[topic] = callback
        if topic in self.slots:
            self.slots[topic].tap = callback

    def add_server(self, server) -> None:
        """A server that lives as long as the node (anything with stop())."""
        self.servers.append(server)

    def destroy_node(self) -> None:
        self.sender.stop()
        self.get_logger().info(f"{self.sender.summary()}; foxglove-sdk threads: "
                               f"{thread_cpu_seconds('tokio'):.2f} s CPU")
        for server in self.servers:
            try:
                server.stop()
            except Exception as exc:  # noqa: BLE001 - stopping is best effort at shutdown
                self.get_logger().warning(f"stopping {server!r}: {exc}")
        self.get_logger().info(f"WebSocket front door: {self.front.accepted} connections passed on, "
                               f"{self.front.cpu:.2f} s CPU piping their bytes")
        if self.refused or self.accepted or self.forwarded:
            self.get_logger().info(f"client input: {self.accepted} accepted ({self.clamped} clamped), refused: "
                                   f"{dict(self.refused) or 'none'}")
        if self.forwarded:
            self.get_logger().info(f"client input: {self.forwarded} forwarded (stamped with a /clock from the "
                                   "domain, which this node cannot vouch is the run's)")
        super().destroy_node()

    # -- topics ----------------------------------------------------------------------------
    def add_topic(self, topic: str, full_type: str, transient_local: bool) -> bool:
        """Serve a topic (once); False if its type's definition is not installed."""
        if topic in self.slots:
            return True
        try:
            schema = self._foxglove.Schema(name=full_type, encoding="ros2msg",
                                           data=message_definition(full_type).encode())
            msg_class = _import_type(full_type)
        except (OSError, LookupError, ImportError, AttributeError, ValueError):
            self.complaints("unknown type", f"{topic}: type {full_type} not installed here: not served", "warning")
            return False
        # the order publisher and the topic's type first: the channel is advertised to clients at
        # once (foxglove-sdk's thread), and a client may advertise its own channel on it before
        # this thread has gone on (client_advertise reads _topic_types)
        if full_type in client_input.CHECKS:
            self._input_pubs[topic] = self.create_publisher(msg_class, topic, rc.COMMAND_QOS)
        self._topic_types[topic] = full_type
        channel = self._foxglove.Channel(topic, schema=schema, message_encoding="cdr", context=self.fg_context)
        slot = self.slots[topic] = TopicSlot(topic, full_type, policy_of(topic, full_type), channel)
        slot.tap = self._taps.get(topic)
        if topic not in self.offered:
            self.create_subscription(msg_class, topic, slot.offer if topic != "/clock" else self._on_clock,
                                     subscription_qos(topic, transient_local), raw=True)
        return True

    def discover(self) -> None:
        for topic, types in self.get_topic_names_and_types():
            if topic in self.slots or topic.startswith(("/rosout", "/parameter_events")) or len(types) != 1:
                continue
            infos = self.get_publishers_info_by_topic(topic)
            if not infos:
                continue
            latched = any(i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for i in infos)
            self.add_topic(topic, types[0], latched)

    def offer(self, topic: str, data: bytes) -> None:
        """A message of a served topic, handed over in this process."""
        if topic == "/clock":
            self._on_clock(data, own=True)
            return
        slot = self.slots.get(topic)
        if slot is not None:
            slot.offer(data)

    def _on_clock(self, data: bytes, own: bool = False) -> None:
        """A /clock message: own (handed over in this process by the runner) or from the domain."""
        if len(data) >= 12:
            sec, nanosec = _STAMP.unpack_from(data, 4)
            t = max(0, sec) * 1_000_000_000 + min(nanosec, 999_999_999)
            if own:
                self.sim_time_ns = self.order_time_ns = t
            elif not self.own_clock:
                why = self.clock_guard.observe(t, time.monotonic())
                if why is None:
                    self.sim_time_ns = self.order_time_ns = t
                else:
                    self.refused["clock"] += 1
                    self.complaints("clock", f"{why}; orders keep the stamp {self.order_time_ns * 1e-9:.3f} s",
                                    "warning")
        slot = self.slots.get("/clock")
        if slot is not None:
            slot.offer(data)

    def send(self) -> bool:
        """The sender's round: what is new goes to the subscribed clients, logged at the simulation
        time. True if the simulation ran since the last round: its time advanced (without /clock:
        a message other than the /tf_static repeat was new)."""
        now = time.monotonic()
        t = self.sim_time_ns
        advanced, self._round_time = t != self._round_time, t
        fresh = False
        for slot in list(self.slots.values()):
            messages = slot.take(now)
            if not messages:
                continue
            fresh = fresh or slot.policy != "static"
            if not slot.channel.has_sinks():
                continue
            for data in messages:
                slot.channel.log(data, log_time=t)
            slot.sent += len(messages)
        self.server.broadcast_time(t)
        return advanced if t else fresh

    # -- client input ---------------------------------------------------------------------
    def _refuse(self, kind: str, text: str) -> None:
        self.refused[kind] += 1
        if self.complaints("client " + kind, f"client input refused: {text}", "warning"):
            try:
                self.server.publish_status(f"refused: {text}", self._foxglove.StatusLevel.Warning,
                                           "live_view_refused")
            except Exception:  # noqa: BLE001 - telling the clients is a courtesy
                pass

    def check_connection(self, headers: Dict[str, str], port: int) -> Optional[Tuple[str, str]]:
        """(kind, why) a connection to port with these request headers is refused, or None."""
        why = self.web_policy.host_refusal(headers.get("host"), port)
        if why is not None:
            return "host", why
        why = self.web_policy.origin_refusal(headers.get("origin"))
        return ("origin", why) if why is not None else None

    def refuse_connection(self, kind: str, why: str) -> None:
        """A connection refused by a front door (WebSocket or HTTP): counted and logged."""
        self.refused[kind] += 1
        self.complaints("connection " + kind, f"connection refused: {why}", "warning")

    def client_advertise(self, client_id: int, channel) -> None:
        key = (client_id, channel.id)
        full_type = self._topic_types.get(channel.topic)
        why = None
        if sum(1 for c, _ in self.client_channels if c == client_id) >= MAX_CLIENT_CHANNELS:
            why = f"client {client_id} advertises more than {MAX_CLIENT_CHANNELS} channels"
        elif full_type not in client_input.CHECKS or channel.topic not in self._input_pubs:
            why = (f"client {client_id} advertised '{channel.topic[:200]}': clients may publish only on the vessel "
                   f"command and rope winch topics ({', '.join(sorted(self._input_pubs)) or 'none here'})")
        elif channel.encoding not in client_input.ENCODINGS:
            why = f"client {client_id} advertised {channel.topic} with encoding {channel.encoding[:50]!r}"
        elif channel.encoding == "cdr" and not client_input.schema_matches(full_type, channel.schema_name):
            why = (f"client {client_id} advertised {channel.topic} as {channel.schema_name[:100]!r}, "
                   f"expected {full_type}")
        if why is not None:
            if len(self._refused_channels) < 10_000:
                self._refused_channels[key] = why
            self._refuse("channel", why)
            return
        self.client_channels[key] = (channel.topic, full_type, channel.encoding)

    def _rate_ok(self, client_kind: str, full_type: str, label: str) -> bool:
        """One shared bucket per kind of client and kind of order (trust.SharedLimits)."""
        order_kind = full_type.rsplit("/", 1)[-1]
        if self.limits.take(client_kind, order_kind, time.monotonic()):
            return True
        self._refuse("rate", f"{label}: more than {self.get_parameter('input_rate').value:g} messages/s of "
                             f"{order_kind} from the {client_kind} clients together")
        return False

    def _check_and_publish(self, label: str, topic: str, full_type: str, encoding: str,
                           data: bytes) -> Tuple[str, str, Tuple[str, ...]]:
        """client_input's checks, then publish the order written anew: (outcome, why not, clamp
        notes); outcome 'accepted' (stamped with the run's own clock), 'forwarded' (stamped with
        the guarded /clock of the domain) or 'message' (refused)."""
        try:
            order = client_input.check(full_type, data, encoding, self.order_time_ns)
        except client_input.InputRefused as exc:
            self._refuse("message", f"{topic} from {label}: {exc}")
            return "message", str(exc), ()
        if order.notes:
            self.clamped += 1
            self.complaints("client clamped", f"{topic} from {label}: {'; '.join(order.notes)}", "warning")
        self._input_pubs[topic].publish(order.data)
        if self.own_clock:
            self.accepted += 1
            return "accepted", "", order.notes
        self.forwarded += 1
        return "forwarded", ("published, stamped with the /clock of the domain, which this live view cannot vouch "
                             "is the run's: the vessel decides"), order.notes

    def client_message(self, client_id: int, channel_id: int, data: bytes) -> None:
        try:
            target = self.client_channels.get((client_id, channel_id))
            if target is None:
                why = self._refused_channels.get((client_id, channel_id), f"channel {channel_id} was never advertised")
                self._refuse("channel", f"message on a refused channel ({why})")
                return
            topic, full_type, encoding = target
            closed = self.orders_closed()
            if closed is not None:
                self._refuse("ended", f"{topic} from client {client_id}: {closed}")
                return
            if not self._rate_ok("websocket", full_type, f"client {client_id}"):
                return
            self._check_and_publish(f"client {client_id}", topic, full_type, encoding, data)
        except Exception as exc:  # noqa: BLE001 - called by foxglove-sdk: nothing may escape into its thread
            self._refuse("error", f"client {client_id}: {type(exc).__name__}: {str(exc)[:200]}")

    def take_input(self, client: str, topic: str, data: bytes, encoding: str = "json",
                   client_kind: str = "http") -> Tuple[str, str, Tuple[str, ...]]:
        """An order from another front end (the instructor station: client 'http <address>'), with the
        WebSocket clients' checks and counts, and its own kind's rate limit: (outcome, why, clamp
        notes), outcome one of 'accepted', 'forwarded', 'ended' (the run or replay has ended, or a replay:
        nothing obeys orders), 'rate', 'topic', 'message'."""
        slot = self.slots.get(topic)
        if slot is None or slot.full_type not in client_input.CHECKS or topic not in self._input_pubs:
            why = (f"{client} may publish only on the vessel command and rope winch topics "
                   f"({', '.join(sorted(self._input_pubs)) or 'none here'}), not '{topic[:200]}'")
            self._refuse("channel", why)
            return "topic", why, ()
        closed = self.orders_closed()
        if closed is not None:
            self._refuse("ended", f"{topic} from {client}: {closed}")
            return "ended", closed, ()
        if not self._rate_ok(client_kind, slot.full_type, client):
            return "rate", f"more than {self.get_parameter('input_rate').value:g} messages/s", ()
        return self._check_and_publish(client, topic, slot.full_type, encoding, data)

    def input_topics(self) -> List[str]:
        """The topics clients may publish on (vessel commands, rope winches)."""
        return sorted(self._input_pubs)


def main(args: Optional[List[str]] = None) -> int:
    return rc.run_node(LiveViewNode, "live_view", args, bad_input=(ValueError, KeyError, OSError, RuntimeError))


if __name__ == "__main__":
    sys.exit(main())
