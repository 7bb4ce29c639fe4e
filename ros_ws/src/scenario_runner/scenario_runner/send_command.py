"""Send one order to a vessel from the terminal (ros2cli's `topic pub` is not available here).

    ros2 run scenario_runner send_command tug --engine 0.5 --steering-deg 10
    ros2 run scenario_runner send_command tug --steering-deg -10     # the engine stays as it is
    ros2 run scenario_runner send_command s175 --anchor let_go
    ros2 run scenario_runner send_command tug --hand-back engine,helm

An order from here is a manual order: the scenario's scripted orders for the controls it changes
yield from then on (docs/scenarios.md, "Who gives the orders"), until --hand-back gives them
back (engine, helm, anchor, winch, or all; a winch is handed back with the rope's name:
send_command towline --hand-back winch). A hand-back is a tug_msgs/ScenarioEvent of kind
hand_back on /scenario/events, which the scenario runner answers with manual_handed_back.

An order sets what it names: an engine or helm left out is sent as the vessel holds it (read
from its /<vessel>/status, waited for up to --wait s), so `--steering-deg -10` alone moves the
helm and leaves the engine. Publishes a tug_msgs/VesselCommand on /<vessel>/command once a subscriber is matched, then
exits. The order is stamped with the simulation time (the newest /clock) whenever /clock is
published, else with wall time (sim_plumbing.sim_time); it says which. A /clock publisher is
looked for for up to CLOCK_DISCOVERY s (a new process sees a running one within 0.03-2.9 s here),
so without one the order goes out that much later. Exit status 1 if no vessel node listens
within --wait seconds, 2 for a value that is not a finite number (the vessel would reject it anyway).
"""
from __future__ import annotations

import argparse
import math
import sys
import time

import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
from tug_msgs.msg import ScenarioEvent, VesselCommand, VesselStatus

from scenario_runner.order_owner import HAND_BACK, VESSEL_CONTROLS, WINCH
from sim_plumbing import ros_common as rc
from sim_plumbing.sim_time import SimClock

# s to look for a /clock publisher (DDS discovery: a new process sees a running node within 0.03-2.9 s on
# this machine, README "The step protocol"); measured: with 1 s, 1 of 2 sends in a paced run went out
# on wall time. And s to wait for the first /clock once one is known.
CLOCK_DISCOVERY = 3.0
CLOCK_TIMEOUT = 4.0
# s the readers of the command topic must stay all matched, no new one discovered, before the send
SETTLE = 0.3

ANCHOR_ORDERS = {"none": VesselCommand.ANCHOR_NO_CHANGE, "let_go": VesselCommand.ANCHOR_LET_GO,
                 "heave_up": VesselCommand.ANCHOR_HEAVE_UP}


def parse_args(argv):
    p = argparse.ArgumentParser(prog="send_command", description=__doc__.split("\n\n")[0])
    p.add_argument("vessel", help="vessel name (its ROS namespace), e.g. tug")
    p.add_argument("--engine", type=float, default=None,
                   help="engine order, fraction of rated rpm: -1 full astern .. 1 full ahead (default: as held)")
    p.add_argument("--steering-deg", type=float, default=None,
                   help="rudder or bucket angle in degrees, positive turns to port (default: as held)")
    p.add_argument("--anchor", choices=sorted(ANCHOR_ORDERS), default="none", help="anchor order")
    p.add_argument("--hand-back", metavar="CONTROLS", nargs="?", const="all",
                   help="give controls back to the scenario's script instead of sending an order: comma-separated "
                        f"{', '.join(VESSEL_CONTROLS + (WINCH,))} or all (default all)")
    p.add_argument("--wait", type=float, default=10.0, help="seconds to wait for the vessel node (default 10)")
    args = p.parse_args(argv)
    orders = [a.split("=")[0] for a in argv if a.split("=")[0] in ("--engine", "--steering-deg", "--anchor")]
    if args.hand_back is not None and orders:
        p.error(f"--hand-back gives controls back to the script; {', '.join(orders)} would be an order: one or the "
                "other")
    if args.hand_back is not None:
        controls = [c.strip() for c in args.hand_back.split(",") if c.strip()]
        unknown = sorted(set(controls) - set(VESSEL_CONTROLS + (WINCH, "all")))
        if unknown or not controls:
            p.error(f"--hand-back {args.hand_back!r}: expected {', '.join(VESSEL_CONTROLS + (WINCH,))} or all, "
                    "comma-separated")
        args.hand_back = ",".join(controls)
    return args


def _wait_for_readers(node, pub, topic: str, deadline: float, spin, wanted: str = "") -> bool:
    """Wait until every reader of topic the graph knows of (the vessel, a recorder, a console) has
    matched, the graph shows a reader of the namespace `wanted` (the vessel node: the runner's
    readers, discovered with /clock, can be all matched before the vessel's is known), and the
    graph has shown no new one for SETTLE s: a volatile sample published before a reader matches
    never reaches it. False if no reader matched by the deadline (with the vessel matched, a reader
    still discovering at the deadline gets nothing)."""
    settled_since = None
    while True:
        now = time.monotonic()
        found = not wanted or any(i.node_namespace.rstrip("/") == wanted
                                  for i in node.get_subscriptions_info_by_topic(topic))
        if found and 0 < pub.get_subscription_count() >= node.count_subscribers(topic):
            settled_since = settled_since or now
            if now - settled_since >= SETTLE:
                return True
        else:
            settled_since = None
        if now > deadline:
            return pub.get_subscription_count() > 0
        spin(0.05)


def _held_orders(node, name: str, spin, deadline: float):
    """(engine order, steering angle in rad) the vessel holds, from its next status; False if none
    comes by the deadline."""
    seen = []
    sub = node.create_subscription(VesselStatus, f"/{name}/status", seen.append, rc.STATE_QOS)
    try:
        while not seen and time.monotonic() < deadline:
            spin(0.05)
    finally:
        node.destroy_subscription(sub)
    return (seen[-1].engine_order, seen[-1].steering_angle_ordered) if seen else False


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(rclpy.utilities.remove_ros_args(argv))
    for name, value in (("--engine", args.engine), ("--steering-deg", args.steering_deg), ("--wait", args.wait)):
        if value is not None and not math.isfinite(value):
            sys.stderr.write(f"send_command: {name} {value!r}: expected a finite number\n")
            return 2
    rc.init_rclpy(argv)
    node = Node("send_command")
    try:
        name = args.vessel.strip('/')
        hand_back = args.hand_back is not None
        topic = rc.EVENTS_TOPIC if hand_back else f"/{name}/command"
        pub = (node.create_publisher(ScenarioEvent, topic, rc.EVENTS_QOS) if hand_back else
               node.create_publisher(VesselCommand, topic, rc.COMMAND_QOS))
        clock = SimClock(node)
        spin = lambda timeout_sec: rclpy.spin_once(node, timeout_sec=timeout_sec)  # noqa: E731
        # The clock first: once its publisher (the runner) is discovered, so are the runner's readers
        # (its recorder) in all but a rare case, which the settling below covers.
        clock.wait(spin, timeout=CLOCK_TIMEOUT, discovery=CLOCK_DISCOVERY)
        if not _wait_for_readers(node, pub, topic, time.monotonic() + args.wait, spin,
                                 wanted="" if hand_back else f"/{name}"):
            listener = "the scenario runner" if hand_back else f"the vessel node for '{args.vessel}'"
            sys.stderr.write(f"send_command: no subscriber on {topic} after {args.wait:g} s "
                             f"(is {listener} running, same ROS_DOMAIN_ID?)\n")
            return 1
        if hand_back:
            msg = ScenarioEvent(source=node.get_fully_qualified_name(), kind=HAND_BACK, target=name,
                                detail=args.hand_back, value=math.nan)
        else:
            held = _held_orders(node, name, spin, time.monotonic() + args.wait) \
                if args.engine is None or args.steering_deg is None else None
            if held is False:
                sys.stderr.write(f"send_command: no /{name}/status within {args.wait:g} s, so the orders it holds are "
                                 "not known: give both --engine and --steering-deg\n")
                return 1
            if args.engine is None:
                args.engine = held[0]
            steering = math.radians(args.steering_deg) if args.steering_deg is not None else held[1]
            args.steering_deg = math.degrees(steering)
            msg = VesselCommand(engine_order=args.engine, steering_angle=steering, anchor=ANCHOR_ORDERS[args.anchor])
        spin(0.0)
        msg.header.stamp = clock.now()
        pub.publish(msg)
        # Reliable delivery: wait for the subscribers' acknowledgement before the process ends.
        # A reader that has not yet matched us asks for the sample at the writer's next
        # heartbeat (Fast DDS: every 3 s), hence the generous limit.
        if not pub.wait_for_all_acked(Duration(seconds=10.0)):
            sys.stderr.write(f"send_command: {topic} did not acknowledge the command within 10 s\n")
            return 1
        if hand_back:
            print(f"sent to {topic}: hand back {args.hand_back} of {name} to the script; stamped "
                  f"{msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9:.3f} s, {clock.source}")
            return 0
        print(f"sent to {topic}: engine {args.engine:+.2f}, steering {args.steering_deg:+.1f} deg, "
              f"anchor {args.anchor}; stamped {msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9:.3f} s, "
              f"{clock.source}")
        return 0
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
