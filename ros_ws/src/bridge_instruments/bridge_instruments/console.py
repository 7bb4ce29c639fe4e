"""A terminal console to drive one vessel of a running simulation (a paced, realtime run).

    ros2 run bridge_instruments console tug --scenario default_demo.yaml

Keys (controls.HELP): engine order in steps of 0.1, helm in steps of 5 deg, winch pay out /
heave in / hold, anchor let go / heave up; a joystick (SDL through pygame) when one is present.
It shows speed over ground (kn), heading (deg true), rate of turn (deg/min to port or stbd),
engine order (two decimals and % ahead / astern) and shaft rpm, helm ordered and actual (deg
port or stbd), roll and pitch (the totals the odometry carries: heel + the wave-frequency roll,
trim + pitch; degrees, roll to starboard or port, pitch bow up or down), the encountered sea
(significant height, encounter period, where it comes from relative to the bow; "calm" without
waves), each towline's tension against its breaking load, the girting ratio against its
threshold, and a warning when either comes near its limit (80 %). Angles are in words (port /
stbd); the few signed numbers follow REP-103 (+ to port, heel + starboard side down, trim + bow
down), as a line on the screen says. With --scenario, only the gauges and keys the vessel's ship
file has (an unpowered barge: no engine, rpm or helm).

What happens is shown as it happens (/scenario/events): a parted towline (PARTED instead of its
tension, within one display period), a grounding, the anchor dragging over the bottom, no data
from the vessel for STALE_AFTER s (its node stopped, the run or replay ended), the end of the run
(scenario_finished); every event's text in the events area, those of a person taking over or
handing back a vessel's orders (manual_order / manual_handed_back) highlighted. Once the run has
finished or the vessel is silent, keys send nothing and the screen says why.

It is an ordinary outside controller: tug_msgs/VesselCommand on /<vessel>/command and
tug_msgs/WinchCommand on /<rope>/winch, stamped with simulation time whenever /clock is
published (sim_plumbing.sim_time), sent the moment a key is pressed.
"""
from __future__ import annotations

import argparse
import collections
import math
import os
import sys
import threading
import time
from typing import Deque, Dict, List, NamedTuple, Optional, Tuple

import rclpy
from rclpy.node import Node

from bridge_instruments import controls
from sim_contract import geo
from sim_contract import topics as T
from scenario_format.particulars import breaking_loads, particulars, scenario_path
from scenario_format.scenario import load_scenario, resolve
from sim_math.rotations import yaw_from_quaternion
from sim_plumbing import ros_common as rc

ANCHOR = {"let_go": 1, "heave_up": 2}
ANCHOR_DREDGING = 3  # tug_msgs/VesselStatus.ANCHOR_DREDGING: on the bottom, dragged along it
DISPLAY_PERIOD = 0.1  # s between screen refreshes
STALE_AFTER = 1.0  # s (10 display periods) without odometry or status: the vessel is silent
EVENT_LINES = 6  # newest events shown
# event kinds shown highlighted: who holds the orders, and what a person must see at once
OWNERSHIP_KINDS = ("manual_order", "manual_handed_back")
ALARM_KINDS = ("rope_parted", "rope_failed", "grounded", "contact_failed", "scenario_finished")
SIGNS = ("signs: angles in words (port / stbd); signed numbers as REP-103: + to port, "
         "heel + stbd side down, trim + bow down")


class Event(NamedTuple):
    t: float  # s, simulation time of the event
    kind: str
    target: str
    detail: str
    value: float


class ConsoleNode(Node):
    """Subscriptions and publishers of the console; state read by the screen thread."""

    def __init__(self, vessel: str, ropes: List[Tuple[str, str, bool]], **kwargs):
        from geometry_msgs.msg import WrenchStamped
        from nav_msgs.msg import Odometry
        from tug_msgs.msg import ScenarioEvent, VesselCommand, VesselStatus, WinchCommand
        from sim_plumbing.sim_time import SimClock
        super().__init__("console", **kwargs)
        self.VesselCommand, self.WinchCommand = VesselCommand, WinchCommand
        self.vessel = vessel
        self.clock = SimClock(self)
        self.odom = None
        self.status = None
        self.heard = 0.0  # time.monotonic() of the newest odometry or status
        self.tension: Dict[str, float] = {}
        self.parted: Dict[str, Event] = {}  # rope -> its rope_parted event
        self.finished: Optional[Event] = None  # the scenario_finished event
        self.events: Deque[Event] = collections.deque(maxlen=EVENT_LINES)
        self.sent = 0
        self.create_subscription(Odometry, T.vessel_topic(vessel, T.ODOM), self._on_odom, rc.STATE_QOS)
        self.create_subscription(VesselStatus, T.vessel_topic(vessel, T.STATUS), self._on_status, rc.STATE_QOS)
        self.create_subscription(ScenarioEvent, T.EVENTS, self._on_event, rc.EVENTS_QOS)
        for rope, end, _winch in ropes:
            self.create_subscription(WrenchStamped, T.end_wrench_topic(rope, end),
                                     lambda m, rope=rope: self._on_wrench(rope, m), rc.STATE_QOS)
        self.cmd_pub = self.create_publisher(VesselCommand, T.vessel_topic(vessel, T.COMMAND), rc.COMMAND_QOS)
        self.winch_pubs = {rope: self.create_publisher(WinchCommand, T.rope_topic(rope, T.WINCH), rc.COMMAND_QOS)
                           for rope, _end, winch in ropes if winch}

    def _on_odom(self, m) -> None:
        self.odom, self.heard = m, time.monotonic()

    def _on_status(self, m) -> None:
        self.status, self.heard = m, time.monotonic()

    def _on_wrench(self, rope: str, m) -> None:
        f = m.wrench.force
        self.tension[rope] = math.sqrt(f.x * f.x + f.y * f.y + f.z * f.z)

    def _on_event(self, m) -> None:
        note_event(self, Event(m.header.stamp.sec + m.header.stamp.nanosec * 1e-9, m.kind, m.target, m.detail,
                               m.value))

    def silent_for(self, now: Optional[float] = None) -> float:
        """s since the vessel's newest odometry or status (0 before the first: still waiting)."""
        return 0.0 if not self.heard else (time.monotonic() if now is None else now) - self.heard

    def why_not_sent(self) -> Optional[str]:
        """Why an order would reach nobody (the run finished, the vessel silent), or None."""
        if self.finished is not None:
            return f"the run finished at t {self.finished.t:.2f} s"
        silent = self.silent_for()
        if silent > STALE_AFTER:
            return f"no data from {self.vessel} for {silent:.0f} s"
        return None

    def send_vessel(self, orders: controls.Orders) -> None:
        msg = self.VesselCommand(engine_order=float(orders.engine), steering_angle=math.radians(orders.helm_deg),
                                 anchor=ANCHOR.get(orders.take_anchor(), 0))
        msg.header.stamp = self.clock.now()
        self.cmd_pub.publish(msg)
        self.sent += 1

    def send_winch(self, orders: controls.Orders) -> None:
        for pub in self.winch_pubs.values():
            msg = self.WinchCommand(payout_rate=float(orders.payout))
            msg.header.stamp = self.clock.now()
            pub.publish(msg)
            self.sent += 1


def note_event(node, ev: Event) -> None:
    """Keep an event for the screen: in the events area, and a parted rope or the end of the run
    as a state the screen shows until the console is closed."""
    node.events.append(ev)
    if ev.kind == "rope_parted":
        node.parted.setdefault(ev.target, ev)
    elif ev.kind == "scenario_finished":
        node.finished = ev
    elif ev.kind == "scenario_started":  # a new run (or a replay looping): a fresh start
        node.parted.clear()
        node.finished = None


def readout(node, orders: controls.Orders, breaking: Dict[str, Optional[float]],
            kit: controls.Equipment = controls.Equipment(), now: Optional[float] = None) -> Tuple[str, list]:
    """The text of the screen and its warnings, from the newest state (`kit`: the gauges the
    vessel has; `now`: time.monotonic() for the silence check)."""
    given = [f"engine {controls.engine_words(orders.engine)}"] if kit.engine else []
    given += [f"helm {controls.side_words(orders.helm_deg)}"] if kit.helm else []
    given += [f"winch {orders.payout:+.1f} m/s"] if node.winch_pubs else []
    lines = [f"{node.vessel.upper()}   orders: {'   '.join(given) or 'none (no engine, helm or winch)'}   "
             f"(sent {node.sent}, {node.clock.source})", SIGNS]
    warn = run_warnings(node, now)
    od, st = node.odom, node.status
    if od is None or st is None:
        lines.append("waiting for the vessel's state ...")
        return "\n".join(lines), warn
    q, tw = od.pose.pose.orientation, od.twist.twist
    yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
    t = st.header.stamp.sec + st.header.stamp.nanosec * 1e-9
    lines.append(f"t {t:8.2f} s   speed {geo.knots(math.hypot(tw.linear.x, tw.linear.y)):5.2f} kn   heading "
                 f"{geo.compass_deg(yaw):6.1f} deg true   rate of turn "
                 f"{controls.turn_words(math.degrees(tw.angular.z) * 60.0)}")
    if kit.engine:
        lines.append(f"engine {controls.engine_words(st.engine_order)}   shaft "
                     f"{st.shaft_speed * 60 / (2 * math.pi):+6.1f} rpm (+ ahead)")
    if kit.helm:
        lines.append(f"rudder {controls.side_words(math.degrees(st.steering_angle))} "
                     f"(ordered {controls.side_words(math.degrees(st.steering_angle_ordered))})")
    lines.append(attitude_line(st))
    lines.append(sea_line(st))
    if st.girting_threshold > 0.0:  # 0: no roll model, no girting (a barge, a planing boat)
        lines.append(f"girting ratio {st.girting_ratio:.2f} of limit {st.girting_threshold:.2f}")
    warn += controls.warnings(st.girting_ratio, st.girting_threshold, 0.0, None)
    if st.girting_warning and not any(w.startswith("GIRTING") for w in warn):
        warn.append("GIRTING WARNING")
    if st.grounded:
        warn.append(f"AGROUND: under-keel clearance {st.under_keel_clearance:+.2f} m (depth {st.water_depth:.2f} m)")
    if st.anchor_state == ANCHOR_DREDGING:
        warn.append(f"ANCHOR DRAGGING over the bottom (dredging) at "
                    f"{geo.knots(math.hypot(tw.linear.x, tw.linear.y)):.1f} kn")
    for rope, tension in sorted(node.tension.items()):
        if rope in node.parted:
            ev = node.parted[rope]
            lines.append(f"{rope}: PARTED at t {ev.t:.2f} s" +
                         (f" ({ev.value / 1e3:.1f} kN)" if math.isfinite(ev.value) else ""))
            continue
        bl = breaking.get(rope)
        lines.append(f"{rope}: tension {tension / 1e3:6.1f} kN" +
                     (f" of breaking load {bl / 1e3:.1f} kN ({100 * tension / bl:.0f} %)" if bl else ""))
        warn += controls.warnings(0.0, 0.0, tension, bl)
    return "\n".join(lines), warn


def run_warnings(node, now: Optional[float] = None) -> List[str]:
    """The alarms that hold whatever the vessel's state: parted lines, the end of the run, a
    silent vessel."""
    warn = [f"{rope.upper()} PARTED at t {ev.t:.2f} s" + (f" ({ev.value / 1e3:.1f} kN)" if math.isfinite(ev.value)
                                                          else "")
            for rope, ev in sorted(node.parted.items())]
    if node.finished is not None:
        warn.append(f"RUN FINISHED at t {node.finished.t:.2f} s: orders are no longer obeyed (keys send nothing)")
    else:
        silent = node.silent_for(now)
        if silent > STALE_AFTER:
            warn.append(f"NO DATA from {node.vessel} for {silent:.0f} s: its node stopped, or the run or replay "
                        "ended (keys send nothing)")
    return warn


def event_lines(node) -> List[Tuple[str, str]]:
    """(text, style) of the newest events, oldest first: every event's own words, who holds the
    orders in bold yellow, alarms in bold red."""
    out = []
    for ev in node.events:
        style = "bold yellow" if ev.kind in OWNERSHIP_KINDS else "bold red" if ev.kind in ALARM_KINDS else ""
        target = f" {ev.target}" if ev.target else ""
        out.append((f"t {ev.t:8.2f} s  {ev.kind}{target}: {ev.detail}", style))
    return out


def attitude_line(st) -> str:
    """Roll and pitch of a tug_msgs/VesselStatus in words: the totals (heel + roll, trim + pitch,
    REP-103: roll + starboard side down, pitch + bow down), and the heave."""
    roll, pitch = math.degrees(st.heel + st.roll), math.degrees(st.trim + st.pitch)
    side = "stbd" if roll > 0.05 else "port" if roll < -0.05 else "    "
    bow = "bow down" if pitch > 0.05 else "bow up  " if pitch < -0.05 else "level   "
    return (f"roll {abs(roll):4.1f} deg {side} (heel {math.degrees(st.heel):+5.1f})   pitch {abs(pitch):4.1f} deg "
            f"{bow} (trim {math.degrees(st.trim):+5.1f})   heave {st.heave:+5.2f} m")


def sea_line(st) -> str:
    """The sea the vessel meets (status' sea block): Hs, encounter period, the angle it comes
    from relative to the bow (0 head seas, + from port), the surface at the vessel."""
    hs = st.wave_significant_height
    if not hs > 0.0:
        return "sea calm"
    te = st.wave_encounter_period
    angle = math.degrees(st.wave_encounter_angle)
    a = abs(angle)
    side = "" if a < 0.5 or a > 179.5 else " port" if angle > 0 else " stbd"
    kind = ("head seas" if a <= 30 else "on the bow" if a < 60 else "beam seas" if a <= 120 else
            "on the quarter" if a < 150 else "following seas")
    return (f"sea Hs {hs:4.1f} m   encounter period {f'{te:5.1f} s' if math.isfinite(te) else '  inf'}   from "
            f"{a:3.0f} deg{side} ({kind})   surface {st.wave_elevation:+5.2f} m")


class Joystick:
    """The first SDL joystick (pygame), if any: axis 1 throttle, axis 0 rudder."""

    def __init__(self):
        self.stick = None
        try:
            os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
            os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
            import pygame
            pygame.display.init()
            pygame.joystick.init()
            if pygame.joystick.get_count() > 0:
                self.stick = pygame.joystick.Joystick(0)
                self.pygame = pygame
        except Exception:  # noqa: BLE001 - no SDL, no device: keys only
            self.stick = None

    def axes(self) -> Optional[Tuple[float, float]]:
        if self.stick is None:
            return None
        self.pygame.event.pump()
        try:
            return self.stick.get_axis(1), self.stick.get_axis(0)
        except Exception:  # noqa: BLE001 - unplugged
            self.stick = None
            return None


def build_app(node: ConsoleNode, orders: controls.Orders, breaking, joystick: Joystick,
              kit: controls.Equipment = controls.Equipment()):
    from rich.text import Text
    from textual.app import App, ComposeResult
    from textual.widgets import Static

    class ConsoleApp(App):
        CSS = "#warn {color: red; text-style: bold;} #note {color: yellow;} #help {color: grey;}"

        def compose(self) -> ComposeResult:
            yield Static("", id="state")
            yield Static("", id="warn")
            yield Static("", id="events")
            yield Static("", id="note")
            yield Static(controls.HELP, id="help")

        def on_mount(self) -> None:
            self.set_interval(DISPLAY_PERIOD, self.refresh_state)
            if joystick.stick is not None and kit.engine:
                self.set_interval(0.02, self.poll_joystick)

        def refresh_state(self) -> None:
            if node.status is not None and time.monotonic() > orders.last_key + 1.0:
                # follow the orders the vessel holds (the scenario's, another controller's) while
                # no key is being pressed: a key steps from what is held, not from stop
                orders.sync(node.status.engine_order, math.degrees(node.status.steering_angle_ordered))
            text, warn = readout(node, orders, breaking, kit)
            self.query_one("#state", Static).update(text)
            self.query_one("#warn", Static).update("\n".join(warn))
            events = Text("events:" if node.events else "events: none yet")
            for line, style in event_lines(node):
                events.append("\n" + line, style=style)
            self.query_one("#events", Static).update(events)

        def poll_joystick(self) -> None:
            axes = joystick.axes()
            if axes is not None and orders.joystick(*axes) and node.why_not_sent() is None:
                node.send_vessel(orders)

        def on_key(self, event) -> None:
            if event.key in ("q", "ctrl+c"):
                self.exit()
                return
            note = self.query_one("#note", Static)
            lacking = controls.lacks(event.key, kit)
            if lacking is not None:
                note.update(Text(f"key {event.key!r} ignored: {node.vessel} has no {lacking}"))
                return
            why = node.why_not_sent()
            if why is not None and controls.KEYS.get(event.key):
                note.update(Text(f"order not sent: {why}"))
                return
            what = orders.key(event.key)
            if what is not None:
                orders.last_key = time.monotonic()
                note.update("")
            if what == "vessel":
                node.send_vessel(orders)
            elif what == "winch":
                node.send_winch(orders)

    return ConsoleApp()


def _scenario_setup(vessel: str, scenario: Optional[str]):
    """(ropes at the vessel as (name, end, has winch), breaking loads, the vessel's Equipment)
    from a scenario; ([], {}, everything) without one."""
    if not scenario:
        return [], {}, controls.Equipment()
    from tug_dynamics.ship_file import ship_config
    path = scenario_path(scenario)
    sc = load_scenario(path)
    ropes = []
    for r in sc.ropes:
        for end in "ab":
            if getattr(r, f"end_{end}").split("/")[0] == vessel:
                ropes.append((r.name, end, end == "a" and r.layout == "winch"))
    loads = breaking_loads(particulars(path, sc))
    spec = next((v for v in sc.vessels if v.name == vessel), None)
    if spec is None:
        return ropes, loads, controls.Equipment()
    _, ship = ship_config(resolve("tug_dynamics", "ships", spec.ship_file, path), spec.ship_overrides or None)
    return ropes, loads, controls.equipment(ship)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(prog="console", description=__doc__.split("\n\n")[0])
    p.add_argument("vessel", help="the vessel to drive (its namespace), e.g. tug")
    p.add_argument("--scenario", help="the running scenario (its ropes, winch and breaking loads; the vessel's ship "
                        "file: only the gauges and keys it has)")
    p.add_argument("--max-helm-deg", type=float, default=35.0, help="helm limit of the keys and stick (default 35)")
    p.add_argument("--winch-rate", type=float, default=0.5, help="m/s of a pay-out / heave-in order (default 0.5)")
    args = p.parse_args(rclpy.utilities.remove_ros_args(argv))
    for name in ("max_helm_deg", "winch_rate"):
        v = getattr(args, name)
        if not math.isfinite(v) or not 0 < v <= 90:
            p.error(f"--{name.replace('_', '-')}: expected a number in (0, 90], got {v!r}")
    ropes, breaking, kit = _scenario_setup(args.vessel.strip("/"), args.scenario)
    rc.init_rclpy(argv)
    node = ConsoleNode(args.vessel.strip("/"), ropes)
    executor = rclpy.executors.SingleThreadedExecutor()
    executor.add_node(node)
    stop = threading.Event()

    def spin():
        while not stop.is_set() and rclpy.ok():
            executor.spin_once(timeout_sec=0.05)

    thread = threading.Thread(target=spin, daemon=True)
    thread.start()
    orders = controls.Orders(args.max_helm_deg, args.winch_rate)
    try:
        build_app(node, orders, breaking, Joystick(), kit).run()
    finally:
        stop.set()
        thread.join(2.0)
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
