"""The topic contract, written once (ROS-free): every topic of a run with its type, QoS, frame and
rate, and the one way to spell each topic's name. Nodes, the runner, the recorder, the bridge
instruments and the live view build names with these functions (vessel_topic("tug", ODOM) is
"/tug/odom"); the runner's list of a scenario's topics and the docs' topic reference are built
from these tables. QoS kinds are named here; sim_plumbing.ros_common holds their profiles.

QoS kinds: latched_state (reliable, transient-local, keep last 50: per-step outputs a late
joiner must get), command (offered reliable, volatile, keep last 10; taken keep-all), protocol
(reliable, volatile, keep all: /sim/step and /sim/step_done), clock (reliable, keep last 10),
events (reliable, keep last 100), tf and tf_static (tf2_ros's).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Tuple


@dataclass(frozen=True)
class Topic:
    name: str  # under the node's namespace ("odom", "end_a/wrench"), or global ("/clock")
    type: str  # ROS type, e.g. "nav_msgs/msg/Odometry"
    qos: str  # QoS kind (module docstring)
    frame: str
    rate: str
    taken: bool = False  # an input of the node (subscribed), not an output
    note: str = ""


# names under a vessel's namespace (one vessel_node per vessel, any ship file)
ODOM, ATTACHMENTS, STATUS, MARKERS, COMMAND = "odom", "attachments", "status", "markers", "command"
THRUSTERS, THRUSTER_COMMAND = "thrusters", "thruster_command"
# names under a rope's namespace (one rope_node per rope) and a contact's (one contact_node)
STATE, WINCH = "state", "winch"

VESSEL_TOPICS: Tuple[Topic, ...] = (
    Topic(ODOM, "nav_msgs/msg/Odometry", "latched_state", "pose in map, twist in <vessel>/base_link",
          "every exchange step"),
    Topic(ATTACHMENTS, "tug_msgs/msg/AttachmentArray", "latched_state",
          "positions, velocities in map; orientation of <vessel>/<attachment>", "every exchange step"),
    Topic(STATUS, "tug_msgs/msg/VesselStatus", "latched_state", "<vessel>/base_link", "every exchange step"),
    Topic(MARKERS, "visualization_msgs/msg/MarkerArray", "latched_state", "<vessel>/base_link",
          "marker_rate (default 10 Hz)", note="hull, deck, attachments, name, force arrows"),
    Topic(COMMAND, "tug_msgs/msg/VesselCommand", "command", "body (steering positive to port)", "on demand",
          taken=True),
)
THRUSTER_TOPICS: Tuple[Topic, ...] = (  # vessels with azimuth thrusters
    Topic(THRUSTERS, "tug_msgs/msg/ThrusterStatus", "latched_state", "<vessel>/base_link", "every exchange step"),
    Topic(THRUSTER_COMMAND, "tug_msgs/msg/ThrusterCommand", "command", "body (azimuth 0 = thrust ahead, + to port)",
          "on demand", taken=True),
)
ROPE_TOPICS: Tuple[Topic, ...] = (
    Topic(STATE, "tug_msgs/msg/RopeState", "latched_state", "map", "every exchange step"),
    Topic(MARKERS, "visualization_msgs/msg/MarkerArray", "latched_state", "map", "marker_rate (default 10 Hz)",
          note="line strip, green (slack) to red (breaking load)"),
)
END_WRENCH = Topic("end_<a|b>/wrench", "geometry_msgs/msg/WrenchStamped", "latched_state",
                   "<vessel>/<attachment>", "every exchange step", note="an end on a vessel: the rope's force on it")
END_COUPLING = Topic("end_<a|b>/coupling", "tug_msgs/msg/RopeEndCoupling", "latched_state", "map",
                     "every exchange step",
                     note="an end on a vessel: the force it takes, with its stiffness and damping (world)")
WINCH_TOPIC = Topic(WINCH, "tug_msgs/msg/WinchCommand", "command", "-", "on demand", taken=True,
                    note="ropes with layout winch")
CONTACT_TOPICS: Tuple[Topic, ...] = (
    Topic(STATE, "tug_msgs/msg/HullContact", "latched_state", "map", "every exchange step"),
)
# the run's hull interactions (one interaction_node for every declared pair and bank, namespace
# INTERACTIONS): on each vessel that feels one, the sum of its Wang (1975) passing-ship loads
# and bank suction, from the odometry of the step before
INTERACTIONS = "interactions"
INTERACTION_TOPICS: Tuple[Topic, ...] = (
    Topic("on_<vessel>/wrench", "geometry_msgs/msg/WrenchStamped", "latched_state", "<vessel>/base_link",
          "every exchange step", note="surge and sway force and yaw moment on the vessel from all its "
                                      "interactions (body axes, about midship)"),
)
CLOCK, SIM_STEP, STEP_DONE, EVENTS, TF, TF_STATIC = (
    "/clock", "/sim/step", "/sim/step_done", "/scenario/events", "/tf", "/tf_static")
GLOBAL_TOPICS: Tuple[Topic, ...] = (
    Topic(CLOCK, "rosgraph_msgs/msg/Clock", "clock", "-", "every exchange step", note="the runner's"),
    Topic(SIM_STEP, "tug_msgs/msg/SimStep", "protocol", "-", "every exchange step", note="the runner's trigger"),
    Topic(STEP_DONE, "tug_msgs/msg/StepDone", "protocol", "-", "every exchange step", note="every node's answer"),
    Topic(EVENTS, "tug_msgs/msg/ScenarioEvent", "events", "-", "on events"),
    Topic(TF, "tf2_msgs/msg/TFMessage", "tf", "map -> <vessel>/base_link", "every exchange step"),
    Topic(TF_STATIC, "tf2_msgs/msg/TFMessage", "tf_static", "<vessel>/base_link -> <vessel>/<attachment>",
          "once at start-up"),
)

_VESSEL_NAMES = {t.name for t in VESSEL_TOPICS + THRUSTER_TOPICS}
_ROPE_NAMES = {t.name for t in ROPE_TOPICS} | {WINCH}


def vessel_topic(vessel: str, name: str) -> str:
    """The topic `name` (ODOM, STATUS, ...) of a vessel: /<vessel>/<name>."""
    if name not in _VESSEL_NAMES:
        raise ValueError(f"'{name}' is not a vessel topic ({sorted(_VESSEL_NAMES)})")
    return f"/{vessel}/{name}"


def rope_topic(rope: str, name: str) -> str:
    """The topic `name` (STATE, MARKERS, WINCH) of a rope: /<rope>/<name>."""
    if name not in _ROPE_NAMES:
        raise ValueError(f"'{name}' is not a rope topic ({sorted(_ROPE_NAMES)})")
    return f"/{rope}/{name}"


def end_wrench_topic(rope: str, end: str) -> str:
    """The force of rope end `end` ('a' or 'b') on its attachment: /<rope>/end_<end>/wrench."""
    if end not in ("a", "b"):
        raise ValueError(f"rope end '{end}': expected 'a' or 'b'")
    return f"/{rope}/end_{end}/wrench"


def end_coupling_topic(rope: str, end: str) -> str:
    """Rope end `end`'s force on its vessel with its linearisation: /<rope>/end_<end>/coupling."""
    if end not in ("a", "b"):
        raise ValueError(f"rope end '{end}': expected 'a' or 'b'")
    return f"/{rope}/end_{end}/coupling"


def contact_topic(contact: str) -> str:
    """The state of a hull contact: /<contact>/state."""
    return f"/{contact}/{STATE}"


def interaction_wrench_topic(vessel: str) -> str:
    """The sum of the run's interaction loads on a vessel: /interactions/on_<vessel>/wrench."""
    return f"/{INTERACTIONS}/on_{vessel}/wrench"
