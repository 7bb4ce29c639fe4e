"""The browser instructor station: a page served by the live view node on http://127.0.0.1:8080.

    ros2 run live_view live_view --ros-args -p http_port:=8080      # beside a run or a replay
    ros2 run scenario_runner run_scenario default_demo.yaml --live  # in the runner's process

The page (web/: index.html, app.js, style.css, and three.js from the npm registry, pinned by
web/package-lock.json, installed by scripts/ensure_env.sh and installed into share/live_view/web/
vendor by the build) shows a 3D view of the water, the vessels (the hull of their scene markers),
their attachments and the ropes coloured by tension; gauges per vessel and per rope; a scrolling
plot of the rope tensions; and controls that publish the ordinary VesselCommand and WinchCommand
messages. Nothing is fetched from elsewhere: the server answers only its own files.

Endpoints (HTTP/1.1, this process's threads, never the ROS executor):
  GET  /, /app.js, /style.css, /vendor/...   the page (a fixed list of files, nothing else on disk)
  GET  /api/state    the newest snapshot (JSON), sampled at ``http_rate`` (default 10 Hz) by one
                     thread whatever the number of clients: sim time, per vessel pose, speed (kn),
                     heading (deg true = (90 - yaw) mod 360), engine order and rpm, rudder/bucket
                     angle, heel, girting ratio, roll and pitch (heel + roll, trim + pitch, deg,
                     REP-103), heave, the encountered sea (Hs, encounter period, angle); per
                     rope the polyline of its connections with their tensions, peak tension,
                     breaking load, deployed length, winch order; the tension history of the last
                     HISTORY_SECONDS of simulated time; per vessel also what it can be ordered
                     (`controls`, from its ship file: vessel_controls), grounded and under-keel
                     clearance, anchor dragging, seconds without data (`silent_s`); the run's
                     state (RunState: waiting, live, replay, ended and why, why orders are
                     refused) and the newest EVENTS_KEPT /scenario/events
  GET  /api/scene    per vessel the hull, deck and attachment points (body frame) of its markers
  GET  /api/sea      the run's sea (sea_description): {"waves": null} on a calm sea, else the
                     components of the very WaveField the vessel nodes sample (built here from the
                     same environment text: spectrum, seed and all), amplitude, omega, kx, ky,
                     phase, and the start-up ramp time, which the page sums at each snapshot's
                     simulation time over a grid around the followed vessel (eta = r(t) sum a_i
                     cos(kx_i x + ky_i y - omega_i t + phase_i)). Components rather than a height
                     grid: a few kB once instead of a grid every sample, no sampler CPU in the
                     runner's process, and the page can draw the sea wherever its camera goes.
                     The environment comes from the parameter ``environment`` (run_scenario --live
                     passes the run's, as to its vessel nodes), else from the scenario
                     ``particulars`` names (a recording: its scenario, beside it or in the library)
  POST /api/publish?topic=/<vessel>/command | /<rope>/winch   JSON body as the WebSocket clients
                     send it ({"engine_order": .., "steering_angle": .., "anchor": ..},
                     {"payout_rate": ..}); handed to LiveViewNode.take_input(): client_input.py's
                     checks, the rate limit shared by every HTTP client, refusals logged and
                     counted, out-of-range values clamped. Answers 200 (accepted, with the clamp
                     notes), 202 (forwarded: a stand-alone live view, which cannot vouch for the
                     run's clock, published it; the vessel decides), 409 (refused: nothing would
                     obey it: a replay, or the run or replay has ended; the reason), 400 (refused: malformed,
                     non-finite, unknown fields, too deep or too long a number), 403 (not a command
                     or winch topic), 413 (too large), 415 (not JSON), 429 (rate).

A browser page of another site cannot send orders or read the state: every request's Host must be
exactly this machine's (trust.WebPolicy: localhost, 127.0.0.1 or [::1] with the port; no DNS
rebinding) and an Origin, if sent, this node's own pages' or one of ``allowed_origins`` (403,
counted as "host" / "origin"); a POST must be application/json. More than ``max_clients``
connections at once are answered 503 and counted.
"""
from __future__ import annotations

import collections
import http.server
import json
import math
import os
import sys
import threading
import time
import urllib.parse
from typing import Deque, Dict, List, Optional, Tuple

from live_view import client_input, trust
from sim_contract import topics as T
from sim_contract.geo import KNOT, compass_deg
from scenario_format.particulars import breaking_loads_from
from sim_math.rotations import rpy_from_quaternion

HISTORY_SECONDS = 180.0  # s of simulated time kept for the tension plot
MAX_BODY = client_input.MAX_MESSAGE_BYTES
ANCHOR_STATES = {0: "none", 1: "stowed", 2: "letting go", 3: "dredging", 4: "heaving up"}
ANCHOR_DREDGING = 3  # tug_msgs/VesselStatus.ANCHOR_DREDGING: the anchor on the bottom
ANCHOR_DRAG_KN = 0.3  # kn over the ground with the anchor on the bottom: the anchor is dragging
SILENT_AFTER = 3.0  # s (wall clock) without a message from a vessel: the page says "no data"
EVENTS_KEPT = 60  # the newest /scenario/events shown on the page
REPLAY_NODE = "mcap_replay"  # the node `ros2 run recording replay` publishes from

# The page's files: URL path -> file under the web root (nothing else is served from disk)
FILES = {
    "/": ("index.html", "text/html; charset=utf-8"),
    "/index.html": ("index.html", "text/html; charset=utf-8"),
    "/app.js": ("app.js", "text/javascript; charset=utf-8"),
    "/style.css": ("style.css", "text/css; charset=utf-8"),
    "/vendor/three.module.js": ("vendor/three.module.js", "text/javascript; charset=utf-8"),
    "/vendor/three.core.js": ("vendor/three.core.js", "text/javascript; charset=utf-8"),
    "/vendor/OrbitControls.js": ("vendor/OrbitControls.js", "text/javascript; charset=utf-8"),
}


def _yaw_roll_pitch(q) -> Tuple[float, float, float]:
    roll, pitch, yaw = (float(a) for a in rpy_from_quaternion(q.x, q.y, q.z, q.w))
    return yaw, roll, pitch


def _clean(obj):
    """JSON-safe: non-finite numbers become null (the page shows a dash)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    return obj


def _finite_or_none(v: float) -> Optional[float]:
    return float(v) if math.isfinite(v) else None


def _silent(now: float, slot) -> Optional[int]:
    """Whole seconds (wall clock) since the slot's newest message, 0 under one second: a snapshot
    changes no more than once a second while nothing arrives (the page redraws on change)."""
    if slot is None or not slot.arrived:
        return None
    age = now - slot.arrived
    return 0 if age < 1.0 else int(age)


def rope_polyline(state) -> Tuple[List[List[float]], List[float]]:
    """The rope's connection points (world) and the tension at each: an element chain's N
    elements give N + 1 connections (each element's ends from its centre, axis and length); a
    cable's nodes are its points."""
    poses, lengths, tensions = state.element_poses, list(state.element_lengths), list(state.connection_tensions)
    centres = [(p.position.x, p.position.y, p.position.z) for p in poses]
    if state.model != "element_chain" or len(lengths) != len(poses) or len(tensions) != len(poses) + 1:
        pts = [list(c) for c in centres]
        if len(tensions) != len(pts) and pts:
            # spread the tensions over the points (nearest)
            tensions = [tensions[min(len(tensions) - 1, round(i * (len(tensions) - 1) / max(1, len(pts) - 1)))]
                        if tensions else 0.0 for i in range(len(pts))]
        return pts, tensions
    ends_a, ends_b = [], []
    for p, c, length in zip(poses, centres, lengths):
        q = p.orientation
        # body x axis of the element (points towards end a)
        ax = (1.0 - 2.0 * (q.y * q.y + q.z * q.z), 2.0 * (q.x * q.y + q.w * q.z), 2.0 * (q.x * q.z - q.w * q.y))
        h = 0.5 * length
        ends_a.append([c[0] + h * ax[0], c[1] + h * ax[1], c[2] + h * ax[2]])
        ends_b.append([c[0] - h * ax[0], c[1] - h * ax[1], c[2] - h * ax[2]])
    pts = [ends_a[0]]
    for i in range(1, len(poses)):
        pts.append([(ends_b[i - 1][k] + ends_a[i][k]) / 2.0 for k in range(3)])
    pts.append(ends_b[-1])
    return pts, tensions




def sea_description(environment: str) -> dict:
    """What GET /api/sea answers for a run's environment (the nodes' `environment` parameter
    text): {"waves": null} on a calm sea (no waves, hs 0, or no environment), else {"waves": {hs,
    tp, from_deg, spectrum, depth (m, null = deep), ramp_time (s), amplitude, omega, kx, ky, phase
    (per component: m, rad/s, rad/m, rad/m, rad)}}: the components of the WaveField
    sea_environment builds from it, as the vessel nodes do (Environment.from_parameter), so the
    page's surface is the physics' sea. ValueError for an environment that does not load."""
    from sea_environment.environment import Environment
    from sea_environment.waves import C_KX, C_KY
    if not environment:
        return {"waves": None}
    env, _ = Environment.from_parameter(environment)
    w = env.waves
    if w is None:
        return {"waves": None}
    spec, rows = env.spec.waves, w.rows
    return {"waves": {"hs": spec.hs, "tp": spec.tp, "from_deg": spec.from_deg, "spectrum": spec.spectrum,
                      "depth": w.depth if math.isfinite(w.depth) else None, "ramp_time": w.ramp_time,
                      "amplitude": w.amplitude.tolist(), "omega": w.omega.tolist(), "kx": rows[:, C_KX].tolist(),
                      "ky": rows[:, C_KY].tolist(), "phase": w.phase.tolist()}}


def vessel_controls(cfg: dict, prescribed: bool = False) -> dict:
    """What a vessel of this ship configuration (tug_dynamics.ship_file.ship_config) can be
    ordered, for the page's gauges and controls: engine (propellers, azimuth thrusters or a
    waterjet) and steering (rudders, the thrusters' azimuth or the waterjet's nozzle); nothing on
    a prescribed motion. An unpowered barge: neither."""
    if prescribed:
        return {"engine": False, "steering": False}
    powered = bool(cfg.get("propellers") or cfg.get("thrusters") or cfg.get("waterjet"))
    steered = bool(cfg.get("rudders") or cfg.get("thrusters") or cfg.get("waterjet"))
    return {"engine": powered, "steering": steered}


def controls_of_ship(ship_file: str, overrides: str = "", motion: str = "", relative_to: Optional[str] = None) -> dict:
    """vessel_controls of a ship file (a path, or a name in the installed ships directory) with a
    vessel node's ship_overrides (YAML text) merged over it. ValueError naming the file."""
    import yaml
    from sim_math.data_files import resolve
    from tug_dynamics.ship_file import ShipFileError, ship_config
    path = resolve("tug_dynamics", "ships", ship_file, relative_to)
    try:
        over = yaml.safe_load(overrides) if overrides else None
        _, cfg = ship_config(path, over or None)
    except (ShipFileError, OSError, yaml.YAMLError) as exc:
        raise ValueError(f"{path}: {exc}") from None
    return vessel_controls(cfg, prescribed=bool(motion))


def controls_from_particulars(path: str) -> Dict[str, dict]:
    """vessel -> vessel_controls from a scenario (a path or a library name) or a recording (the
    scenario its particulars name, beside it or in the library; else the ship files its
    particulars name). ValueError naming the file."""
    from scenario_format.particulars import particulars_of_recording, scenario_of_recording, scenario_path
    from scenario_format.scenario import ScenarioError, load_scenario
    scenario, ships = None, {}
    if path.endswith(".mcap"):
        parts = particulars_of_recording(path)
        ships = {v: d.get("ship_file", "") for v, d in (parts.get("vessels") or {}).items()}
        if parts.get("scenario"):
            scenario, _ = scenario_of_recording(path, parts["scenario"])
    else:
        scenario = scenario_path(path)
    if scenario is None:
        return {v: controls_of_ship(f) for v, f in ships.items() if f}
    try:
        sc = load_scenario(scenario, check_files=False)
    except ScenarioError as exc:
        raise ValueError(str(exc)) from None
    import yaml
    return {v.name: controls_of_ship(v.ship_file, yaml.safe_dump(dict(v.ship_overrides)) if v.ship_overrides else "",
                                     "prescribed" if v.motion is not None else "", scenario) for v in sc.vessels}


class RunState:
    """What the page says of the run as a whole, and whether orders can go anywhere.

    state: 'waiting' (no vessel seen yet), 'live' (a run), 'replay' (a recording played by
    `recording replay`, whose node publishes the vessels' topics: nothing obeys orders), 'ended'
    (`ended` says why: the scenario_finished event, or every publisher of the vessels' odometry gone after
    data came: the run's nodes stopped, the replay played out). A new run or replay (a
    scenario_started event, publishers back after all had gone, the simulation time going back)
    makes it live again. ROS-free: fed by the station."""

    def __init__(self):
        self.source: Optional[str] = None  # 'run' or 'replay', from the vessels' publishers
        self.ended: Optional[str] = None
        self.had_data = False
        self.gone = False
        self.last_t: Optional[float] = None

    def _what(self) -> str:
        return "replay" if self.source == "replay" else "run"

    def event(self, kind: str, t: float) -> None:
        if kind == "scenario_started":
            self.ended, self.gone = None, False
        elif kind == "scenario_finished" and self.ended is None:
            self.ended = f"scenario finished at t = {t:.1f} s"

    def stamp(self, t: float) -> None:
        self.had_data = True
        if self.ended is not None and self.last_t is not None and t < self.last_t - 1e-6:
            self.ended, self.gone = None, False  # started again from an earlier time
        self.last_t = t if self.last_t is None else (t if self.ended is None else max(t, self.last_t))

    def publishers(self, nodes: List[str], quiet: bool = True) -> None:
        """The names of the nodes publishing the vessels' odometry now; quiet: no vessel data for
        SILENT_AFTER s (publishers missing while data still flows are a lapse of discovery, not an end)."""
        if nodes:
            self.source = "replay" if REPLAY_NODE in nodes else "run"
            if self.gone:
                self.ended, self.gone = None, False
        elif self.had_data and not self.gone and quiet:
            self.gone = True
            if self.ended is None:
                self.ended = ("the recording has been played" if self.source == "replay" else
                              "the simulation's vessel nodes have stopped")

    @property
    def state(self) -> str:
        if self.ended is not None:
            return "ended"
        if not self.had_data:
            return "waiting"
        return "replay" if self.source == "replay" else "live"

    def orders_closed(self) -> Optional[str]:
        """Why an order goes nowhere now, or None."""
        if self.ended is not None:
            return f"the {self._what()} has ended ({self.ended}): nothing obeys orders any more"
        if self.source == "replay":
            return "a replay of a recording: the recorded vessels obey no orders"
        return None


class InstructorStation:
    """The HTTP server of the page and its sampler thread (see the module docstring). Lives as long
    as the live view node: started by it, stopped with its servers."""

    def __init__(self, node):
        from ament_index_python.packages import PackageNotFoundError, get_package_share_directory
        self.node = node
        self.log = node.get_logger()
        host = node.get_parameter("host").value
        self.loopback = trust.is_loopback_bind(host)
        self.period = 1.0 / node.get_parameter("http_rate").value
        root = node.get_parameter("web_root").value
        if not root:
            try:
                root = os.path.join(get_package_share_directory("live_view"), "web")
            except PackageNotFoundError:
                root = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "web")
        self.web_root = root
        missing = [f for f, _ in FILES.values() if not os.path.isfile(os.path.join(root, f))]
        if missing:
            self.log.warning(f"instructor station: {', '.join(sorted(set(missing)))} missing in {root} (three.js is "
                             "installed by scripts/ensure_env.sh with npm ci; is npm installed?): the page says so")
        self.breaking: Dict[str, Optional[float]] = {}
        particulars = node.get_parameter("particulars").value
        if particulars:
            try:
                self.breaking.update(breaking_loads_from(particulars))
            except Exception as exc:  # noqa: BLE001 - a bad file only costs the breaking loads
                self.log.warning(f"instructor station: no breaking loads from {particulars!r}: {exc}")
        self.controls: Dict[str, dict] = {}  # vessel -> vessel_controls, from particulars or its node
        if particulars:
            try:
                self.controls.update(controls_from_particulars(particulars))
            except Exception as exc:  # noqa: BLE001 - a bad file only costs knowing the controls
                self.log.warning(f"instructor station: no vessel controls from {particulars!r}: {exc}")
        self.run = RunState()
        self._events: Deque[dict] = collections.deque(maxlen=EVENTS_KEPT)
        self._events_lock = threading.Lock()
        node.tap(T.EVENTS, self._on_event)
        node.orders_closed = self.run.orders_closed
        self._sea_json = json.dumps(self._sea(particulars)).encode()
        self._asked: Dict[str, float] = {}
        self._spent_clients: List[object] = []
        self._history: Dict[str, Deque[Tuple[float, float]]] = {}
        self._scene: Dict[str, dict] = {}
        self._state_json = b'{"t": null, "vessels": {}, "ropes": {}, "history": {}}'
        self._last_t: Optional[float] = None
        self.samples = 0
        self.sample_cpu = 0.0  # s of the sampler thread's CPU
        self._stop = threading.Event()
        self._types = None

        station = self

        class Handler(_Handler):
            pass
        Handler.station = station
        self.httpd = _Server((host, node.get_parameter("http_port").value), Handler)
        self.httpd.max_clients = node.get_parameter("max_clients").value
        self.httpd.on_refused = node.refuse_connection
        self.port = self.httpd.server_address[1]
        self.url = f"http://{'localhost' if self.loopback else host}:{self.port}/"
        self._threads = [threading.Thread(target=self.httpd.serve_forever, kwargs={"poll_interval": 0.2},
                                          name="instructor-http", daemon=True),
                         threading.Thread(target=self._sample_loop, name="instructor-sampler", daemon=True)]
        for t in self._threads:
            t.start()
        from rclpy.clock import Clock, ClockType
        self._ask_timer = node.create_timer(2.0, self._ask_nodes, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.log.info(f"instructor station on {self.url} (display period {1000 * self.period:.0f} ms)")

    def _sea(self, particulars: str) -> dict:
        """sea_description of the parameter `environment`, else of the scenario `particulars`
        names; calm (with a note in the log and the answer) when neither gives one."""
        from scenario_format.particulars import environment_of
        text, note = self.node.get_parameter("environment").value, None
        if not text and particulars:
            try:
                text, note = environment_of(particulars)
            except Exception as exc:  # noqa: BLE001 - a bad file only costs the waves
                note = f"no environment from {particulars!r}: {exc}"
        try:
            sea = sea_description(text)
        except Exception as exc:  # noqa: BLE001 - the page shows flat water
            sea, note = {"waves": None}, f"the environment does not load: {exc}"
        if note:
            self.log.warning(f"instructor station: calm sea drawn: {note}")
            sea["note"] = note
        elif sea["waves"] is not None:
            w = sea["waves"]
            self.log.info(f"instructor station: the run's sea, Hs {w['hs']:g} m, Tp {w['tp']:g} s, from "
                          f"{w['from_deg']:g} deg ({len(w['amplitude'])} components)")
        return _clean(sea)

    def sea_json(self) -> bytes:
        return self._sea_json

    def stop(self) -> None:
        self._stop.set()
        self.httpd.shutdown()
        self.httpd.server_close()
        for t in self._threads:
            t.join(2.0)
        self.log.info(f"instructor station: {self.samples} samples, "
                      f"{1000 * self.sample_cpu / max(1, self.samples):.2f} ms CPU each")

    # -- message types (imported once, in the sampler) -------------------------------------
    def types(self):
        if self._types is None:
            from nav_msgs.msg import Odometry
            from rclpy.serialization import deserialize_message
            from tug_msgs.msg import RopeState, ScenarioEvent, VesselCommand, VesselStatus, WinchCommand
            from visualization_msgs.msg import MarkerArray
            self._types = dict(odom=Odometry, status=VesselStatus, state=RopeState, command=VesselCommand,
                               winch=WinchCommand, markers=MarkerArray, event=ScenarioEvent,
                               decode=deserialize_message)
        return self._types

    def _decode(self, topic: str, kind: str):
        slot = self.node.slots.get(topic)
        data = slot.last if slot is not None else None
        if data is None:
            return None
        t = self.types()
        try:
            return t["decode"](data, t[kind])
        except Exception:  # noqa: BLE001 - a message that does not decode is left out
            return None

    # -- events ------------------------------------------------------------------------
    def _on_event(self, data: bytes) -> None:
        """A /scenario/events message as it arrives (the receiving thread): kept for the page's list,
        and the run's start and end."""
        t = self.types()
        try:
            ev = t["decode"](data, t["event"])
        except Exception:  # noqa: BLE001 - a message that does not decode is left out
            return
        stamp = ev.header.stamp.sec + 1e-9 * ev.header.stamp.nanosec
        self.run.event(ev.kind, stamp)
        with self._events_lock:
            if ev.kind == "scenario_started":
                self._events.clear()
            self._events.append({"t": stamp, "step": ev.step, "kind": ev.kind, "target": ev.target,
                                 "detail": ev.detail, "value": _finite_or_none(ev.value),
                                 "source": ev.source})

    # -- what the running nodes say: breaking loads, vessel controls, who publishes ------------
    def _ask_nodes(self) -> None:
        """Timer (ROS executor): the nodes publishing the vessels' odometry (a run's, or a replay's:
        RunState), and the parameters of the nodes whose particulars are not known yet: a rope
        node's rope_file (its breaking load, rope_model.models.load_params), a vessel node's
        ship_file, ship_overrides and motion (its controls, controls_of_ship)."""
        from rcl_interfaces.srv import GetParameters
        now = time.monotonic()
        while self._spent_clients:  # answered (or given up) at an earlier tick
            self.node.destroy_client(self._spent_clients.pop())
        publishers, newest = [], 0.0
        for v in self._names("/odom"):
            publishers += [i.node_name for i in self.node.get_publishers_info_by_topic(T.vessel_topic(v, T.ODOM))]
            newest = max(newest, self.node.slots[T.vessel_topic(v, T.ODOM)].arrived)
        self.run.publishers(publishers, quiet=now - newest >= SILENT_AFTER)
        wanted = [(topic[1:-len("/state")], topic, ["rope_file"], self._take_rope_file)
                  for topic in list(self.node.slots) if topic.endswith("/state") and topic.count("/") == 2]
        wanted += [(v, T.vessel_topic(v, T.ODOM), ["ship_file", "ship_overrides", "motion"], self._take_ship_file)
                   for v in self._names("/odom")]
        for name, topic, names, take in wanted:
            known = self.breaking if take == self._take_rope_file else self.controls
            if name in known or now - self._asked.get(topic, -1e9) < 10.0:
                continue
            infos = [i for i in self.node.get_publishers_info_by_topic(topic) if i.node_name != REPLAY_NODE]
            if not infos:
                continue
            self._asked[topic] = now
            info = infos[0]
            service = f"{info.node_namespace.rstrip('/')}/{info.node_name}/get_parameters"
            client = self.node.create_client(GetParameters, service)
            if not client.service_is_ready():
                self.node.destroy_client(client)
                self._asked[topic] = now - 8.0  # again at the next tick
                continue

            def done(future, name=name, client=client, take=take):
                try:
                    take(name, [p.string_value if p.type == 4 else "" for p in future.result().values])  # STRING
                except Exception as exc:  # noqa: BLE001 - asked again later
                    self.log.debug(f"instructor station: parameters of {name}: {exc}")
                finally:
                    self._spent_clients.append(client)
            client.call_async(GetParameters.Request(names=names)).add_done_callback(done)

    def _take_rope_file(self, rope: str, values: List[str]) -> None:
        if values and values[0]:
            from rope_model.models import load_params
            load = getattr(load_params(values[0]), "breaking_load", None)
            self.breaking[rope] = float(load) if load is not None and math.isfinite(load) else None

    def _take_ship_file(self, vessel: str, values: List[str]) -> None:
        if values and values[0]:
            self.controls[vessel] = controls_of_ship(*values[:3])

    # -- sampling --------------------------------------------------------------------------
    def _sample_loop(self) -> None:
        next_t = time.monotonic()
        while not self._stop.is_set():
            c0 = time.thread_time()
            try:
                self.sample()
            except Exception as exc:  # noqa: BLE001 - the page keeps the last snapshot
                self.node.complaints("instructor sample", f"instructor station: sampling failed: {exc!r}", "warning")
            self.sample_cpu += time.thread_time() - c0
            next_t += self.period
            delay = next_t - time.monotonic()
            if delay < 0:
                next_t, delay = time.monotonic(), 0.0
            self._stop.wait(delay)

    def _names(self, suffix: str) -> List[str]:
        return sorted(t[1:-len(suffix)] for t in self.node.slots if t.endswith(suffix) and t.count("/") == 2)

    def sample(self) -> None:
        """One snapshot of everything the page shows, encoded once for every client."""
        vessels, ropes = {}, {}
        t_sim = None
        now = time.monotonic()
        for v in self._names("/odom"):
            odom = self._decode(T.vessel_topic(v, T.ODOM), "odom")
            if odom is None:
                continue
            status = self._decode(T.vessel_topic(v, T.STATUS), "status")
            slot = self.node.slots.get(T.vessel_topic(v, T.ODOM))
            stamp = odom.header.stamp.sec + 1e-9 * odom.header.stamp.nanosec
            t_sim = stamp if t_sim is None else max(t_sim, stamp)
            p, q, lin = odom.pose.pose.position, odom.pose.pose.orientation, odom.twist.twist.linear
            yaw, roll, pitch = _yaw_roll_pitch(q)
            d = {"t": stamp, "x": p.x, "y": p.y, "z": p.z, "q": [q.x, q.y, q.z, q.w],
                 "speed_kn": math.hypot(lin.x, lin.y) / KNOT, "heading_deg": compass_deg(yaw),
                 "heel_deg": math.degrees(roll), "trim_deg": math.degrees(pitch),
                 "has_command": T.vessel_topic(v, T.COMMAND) in self.node.input_topics(),
                 "controls": self.controls.get(v), "silent_s": _silent(now, slot)}
            if status is not None:
                d.update(step=status.step, engine_order=status.engine_order,
                         rpm=status.shaft_speed * 60.0 / (2.0 * math.pi),
                         steering_deg=math.degrees(status.steering_angle),
                         steering_ordered_deg=math.degrees(status.steering_angle_ordered),
                         heel_deg=math.degrees(status.heel), trim_deg=math.degrees(status.trim),
                         stw_kn=status.speed_through_water / KNOT, thrust=status.thrust,
                         girting_ratio=_finite_or_none(status.girting_ratio),
                         girting_threshold=_finite_or_none(status.girting_threshold),
                         girting_warning=bool(status.girting_warning),
                         anchor=ANCHOR_STATES.get(status.anchor_state, str(status.anchor_state)),
                         roll_deg=math.degrees(status.heel + status.roll),
                         pitch_deg=math.degrees(status.trim + status.pitch), heave=status.heave,
                         wave_elevation=status.wave_elevation, wave_hs=status.wave_significant_height,
                         wave_encounter_period=_finite_or_none(status.wave_encounter_period),
                         wave_encounter_angle_deg=math.degrees(status.wave_encounter_angle),
                         grounded=bool(status.grounded), ukc=_finite_or_none(status.under_keel_clearance),
                         anchor_dragging=(status.anchor_state == ANCHOR_DREDGING and d["speed_kn"] > ANCHOR_DRAG_KN))
            vessels[v] = d
        for r in self._names("/state"):
            state = self._decode(T.rope_topic(r, T.STATE), "state")
            if state is None:
                continue
            stamp = state.header.stamp.sec + 1e-9 * state.header.stamp.nanosec
            t_sim = stamp if t_sim is None else max(t_sim, stamp)
            pts, tensions = rope_polyline(state)
            peak = max(tensions) if tensions else 0.0
            load = self.breaking.get(r)
            winch = self._decode(T.rope_topic(r, T.WINCH), "winch")
            rate = winch.payout_rate if winch is not None else None
            ropes[r] = {"t": stamp, "step": state.step, "model": state.model,
                        "points": [[round(c, 3) for c in p] for p in pts],
                        "tensions": [round(x, 1) for x in tensions], "tension": peak,
                        "tension_a": tensions[0] if tensions else 0.0, "tension_b": tensions[-1] if tensions else 0.0,
                        "breaking_load": load, "ratio": peak / load if load else None,
                        "deployed_length": state.unstretched_length, "stretched_length": state.stretched_length,
                        "broken": bool(state.broken), "payout_rate": rate,
                        "winch": ("no order" if rate is None else "paying out" if rate > 0 else
                                  "heaving in" if rate < 0 else "holding"),
                        "has_winch": T.rope_topic(r, T.WINCH) in self.node.input_topics()}
            hist = self._history.setdefault(r, collections.deque())
            if hist and stamp < hist[-1][0]:  # a new run or a replay started again
                hist.clear()
            if not hist or stamp > hist[-1][0]:
                hist.append((stamp, peak))
            while hist and hist[0][0] < stamp - HISTORY_SECONDS:
                hist.popleft()
        history = {r: [[round(t, 2), round(x, 1)] for t, x in h] for r, h in self._history.items()}
        if vessels:
            self.run.stamp(max(d["t"] for d in vessels.values()))
        with self._events_lock:
            events = list(self._events)
        silent = min((d["silent_s"] for d in vessels.values() if d["silent_s"] is not None), default=None)
        run = {"state": self.run.state, "ended": self.run.ended, "source": self.run.source,
               "orders_closed": self.run.orders_closed(), "silent_s": silent, "silent_after": SILENT_AFTER}
        self._state_json = json.dumps(_clean({
            "t": t_sim, "sample": self.samples, "period": self.period, "vessels": vessels, "ropes": ropes,
            "history": history, "input_topics": self.node.input_topics(), "run": run, "events": events}),
            allow_nan=False).encode()
        self.samples += 1

    def state_json(self) -> bytes:
        return self._state_json

    def scene_json(self) -> bytes:
        """The vessels' hull, deck and attachments from their markers (body frame), once found."""
        for v in self._names("/odom"):
            if v in self._scene:
                continue
            markers = self._decode(T.vessel_topic(v, T.MARKERS), "markers")
            if markers is None:
                continue
            d = {}
            for m in markers.markers:
                key = {0: "hull", 1: "deck", 2: "attachments"}.get(m.id)
                if key is None or not m.frame_locked:
                    continue
                d[key] = [round(c, 3) for p in m.points for c in (p.x, p.y, p.z)]
                if key != "attachments":
                    d[key + "_color"] = [m.color.r, m.color.g, m.color.b]
            if "hull" in d:
                self._scene[v] = d
        return json.dumps({"vessels": self._scene}).encode()

    # -- orders ----------------------------------------------------------------------------
    def publish(self, client: str, topic: str, body: bytes) -> Tuple[int, dict]:
        outcome, why, notes = self.node.take_input(client, topic, body, "json")
        code = {"accepted": 200, "forwarded": 202, "ended": 409, "rate": 429, "topic": 403, "message": 400}[outcome]
        return code, {"accepted": outcome == "accepted", "forwarded": outcome == "forwarded", "outcome": outcome,
                      "topic": topic, "reason": why, "clamped": list(notes)}

    def refuse(self, kind: str, text: str) -> None:
        self.node._refuse(kind, text)


class _Server(http.server.ThreadingHTTPServer):
    """At most max_clients connections at once (a keep-alive connection holds its thread): more are
    answered 503 and counted (on_refused). An error in a handler is counted and logged in one
    line (on_refused), not printed as a traceback."""
    daemon_threads = True
    allow_reuse_address = True
    request_queue_size = 32
    max_clients = 32
    on_refused = staticmethod(lambda kind, why: None)

    def __init__(self, *args, **kwargs):
        self._active = 0
        self._active_lock = threading.Lock()
        super().__init__(*args, **kwargs)

    def process_request(self, request, client_address) -> None:
        with self._active_lock:
            full = self._active >= self.max_clients
            if not full:
                self._active += 1
        if not full:
            super().process_request(request, client_address)
            return
        why = f"more than {self.max_clients} connections at once (parameter max_clients)"
        self.on_refused("connections", f"http {client_address[0]}: {why}")
        body = f"refused: {why}\n".encode()
        try:
            request.settimeout(1.0)
            request.sendall(b"HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain; charset=utf-8\r\n"
                            b"Connection: close\r\nContent-Length: " + str(len(body)).encode() + b"\r\n\r\n" + body)
        except OSError:
            pass
        self.shutdown_request(request)

    def process_request_thread(self, request, client_address) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            with self._active_lock:
                self._active -= 1

    def handle_error(self, request, client_address) -> None:
        exc = sys.exc_info()[1]
        self.on_refused("error", f"http {client_address[0]}: {type(exc).__name__}: {str(exc)[:200]}")


class _Handler(http.server.BaseHTTPRequestHandler):
    station: InstructorStation
    server_version = "tugsim-instructor/1"
    protocol_version = "HTTP/1.1"
    timeout = 30

    def log_message(self, fmt, *args) -> None:  # no line per request
        pass

    def _send(self, code: int, body: bytes, ctype: str = "application/json", cache: bool = False) -> None:
        self.send_response(code)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "max-age=3600" if cache else "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, code: int, obj: dict) -> None:
        self._send(code, json.dumps(obj).encode())

    def _refused_request(self) -> bool:
        """Answer 403 (counted, logged) a request whose Host is not this machine or whose Origin is
        a page of another site (trust.WebPolicy); True if it was."""
        node = self.station.node
        policy = node.web_policy
        host, origin = self.headers.get_all("Host") or [], self.headers.get_all("Origin") or []
        why = policy.host_refusal(", ".join(host) if host else None, self.station.port)
        kind = "host"
        if why is None:
            kind, why = "origin", policy.origin_refusal(", ".join(origin) if origin else None)
        if why is None:
            return False
        self.close_connection = True
        node.refuse_connection(kind, f"http {self.client_address[0]}: {why}")
        self._json(403, {"accepted": False, "reason": why})
        return True

    def do_GET(self) -> None:
        if self._refused_request():
            return
        path = urllib.parse.urlsplit(self.path).path
        if path == "/api/state":
            self._send(200, self.station.state_json())
        elif path == "/api/scene":
            self._send(200, self.station.scene_json())
        elif path == "/api/sea":
            self._send(200, self.station.sea_json())
        elif path in FILES:
            name, ctype = FILES[path]
            try:
                with open(os.path.join(self.station.web_root, name), "rb") as f:
                    body = f.read()
            except OSError:
                self._send(404, f"{name} is missing in {self.station.web_root}: run scripts/ensure_env.sh with npm "
                                f"installed (it installs three.js with npm ci)".encode(), "text/plain; charset=utf-8")
                return
            self._send(200, body, ctype, cache=path.startswith("/vendor/"))
        else:
            self._send(404, b"not found", "text/plain; charset=utf-8")

    do_HEAD = do_GET

    def do_POST(self) -> None:
        client = f"http {self.client_address[0]}"
        path, _, query = self.path.partition("?")
        length = self.headers.get("Content-Length")
        try:
            n = int(length)
        except (TypeError, ValueError):
            n = -1
        if path != "/api/publish":
            self.close_connection = True
            self._json(404, {"accepted": False, "reason": "not found"})
            return
        if self._refused_request():
            return
        if n < 0 or n > MAX_BODY:
            self.close_connection = True
            self.station.refuse("message", f"{client}: a body of {length} bytes (at most {MAX_BODY})")
            self._json(413, {"accepted": False, "reason": f"body must have a length of at most {MAX_BODY} bytes"})
            return
        body = self.rfile.read(n)
        ctype = (self.headers.get("Content-Type") or "").split(";")[0].strip().lower()
        if ctype != "application/json":
            self.station.refuse("message", f"{client}: Content-Type {ctype[:60]!r}, expected application/json")
            self._json(415, {"accepted": False, "reason": "Content-Type must be application/json"})
            return
        topic = urllib.parse.parse_qs(query).get("topic", [""])[0]
        code, answer = self.station.publish(client, topic, body)
        self._json(code, answer)
