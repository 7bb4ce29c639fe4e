"""Each node's parameters, written once (ROS-free): name, default (its type is the ROS parameter
type), description, range and unit, and whether it may change while the node runs.

The nodes declare their ROS parameters from these tables (sim_plumbing.ros_common.declare_table:
a number with a range gets a floating-point or integer range descriptor, the unit in its
description), the scenario format takes its ranges and defaults from them, and the runner maps
a scenario onto them (scenario_runner.run_nodes.node_specs sets only names a table holds). Adding a parameter is
one row here; the docs' parameter reference is generated from these tables.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Dict, Iterator, Optional, Tuple

from sim_contract.equipment import DEFAULT_UTC_START, NMEA_UDP_PORT
from sim_contract.geo import DEFAULT_ORIGIN


@dataclass(frozen=True)
class Param:
    name: str
    default: Any  # float, int, bool, str, or a list of str / float: the ROS parameter's type
    description: str
    lo: Optional[float] = None  # range of a number (inclusive); None: any value of the type
    hi: Optional[float] = None
    unit: str = ""
    live: bool = False  # settable while the node runs (ros2 param set); else fixed at start-up
    choices: Tuple[str, ...] = ()  # the values a string may take (checked by the node and the scenario)
    dynamic: bool = False  # any type (e.g. a list of numbers or the same as a string)
    kind: str = ""  # the ROS type of a parameter without a default (default None: used only when given)
    read_only: bool = False  # set once at start-up by whoever starts the node (ros2 param set refused)

    @property
    def ros_type(self) -> str:
        """The ROS parameter type of the default, as `ros2 param describe` names it."""
        d = self.default
        if d is None and self.kind:
            return self.kind
        if isinstance(d, bool):
            return "bool"
        if isinstance(d, int):
            return "integer"
        if isinstance(d, float):
            return "double"
        if isinstance(d, str):
            return "string"
        if isinstance(d, list) and d and all(isinstance(v, str) for v in d):
            return "string array"
        if isinstance(d, list) and d and all(isinstance(v, float) for v in d):
            return "double array"
        raise TypeError(f"parameter {self.name}: no ROS type for default {d!r}")


class ParamTable:
    """The parameters of one node, in declaration order; table["name"] is its Param."""

    def __init__(self, node: str, *params: Param):
        self.node = node
        self.params: Tuple[Param, ...] = params
        self._by_name: Dict[str, Param] = {p.name: p for p in params}
        if len(self._by_name) != len(params):
            raise ValueError(f"{node}: a parameter is listed twice")
        for p in params:
            p.ros_type  # noqa: B018 - every default has a ROS type
            if (p.lo is None) != (p.hi is None) or (p.lo is not None and p.default is not None
                                                    and not p.lo <= p.default <= p.hi):
                raise ValueError(f"{node}: parameter {p.name}: default {p.default!r} outside [{p.lo}, {p.hi}]")

    def __getitem__(self, name: str) -> Param:
        return self._by_name[name]

    def __contains__(self, name: str) -> bool:
        return name in self._by_name

    def __iter__(self) -> Iterator[Param]:
        return iter(self.params)

    def __add__(self, other: "ParamTable") -> "ParamTable":
        return ParamTable(self.node, *self.params, *other.params)

    @property
    def names(self) -> Tuple[str, ...]:
        return tuple(p.name for p in self.params)

    @property
    def live(self) -> Tuple[str, ...]:
        return tuple(p.name for p in self.params if p.live)

    def check_names(self, names) -> None:
        """ValueError naming any name that is not a parameter of this node (a runner's mapping)."""
        unknown = sorted(set(names) - set(self._by_name))
        if unknown:
            raise ValueError(f"{self.node}: not its parameters: {unknown}")


P = Param

# Every stepped node (sim_plumbing.stepping.SteppedNode.init_stepping).
STEPPING = ParamTable(
    "stepped node",
    P("exchange_rate", 50.0, "Exchange steps per simulated second", 1.0, 1000.0, "Hz"),
    P("lockstep", False, "true: step on the scenario runner's /sim/step triggers; false: free-run on a wall-clock "
                         "timer"),
    P("run_id", "", "Identity of the run (lockstep): triggers of any other run are refused; '' joins the first "
                    "run whose SimStep(0) arrives"),
)

CURRENT_EAST = P("current_east", 0.0, "Uniform current, east component", -10.0, 10.0, "m/s")
CURRENT_NORTH = P("current_north", 0.0, "Uniform current, north component", -10.0, 10.0, "m/s")
MARKER_RATE_HI = 1000.0

# tug_dynamics vessel_node: every ship file.
VESSEL_NODE = ParamTable(
    "tug_dynamics/vessel_node",
    P("ship_file", "", "Ship file: a path, or a file name in share/tug_dynamics/ships (e.g. harbour_tug.yaml)"),
    P("vessel_name", "", "Vessel name used in frames and messages; default: the node's namespace"),
    P("initial_x", 0.0, "Initial east position", -1e7, 1e7, "m"),
    P("initial_y", 0.0, "Initial north position", -1e7, 1e7, "m"),
    P("initial_yaw", 0.0, "Initial heading, 0 = bow east, positive counter-clockwise (REP-103)",
      -2 * math.pi, 2 * math.pi, "rad"),
    P("initial_speed", 0.0, "Initial surge speed", -30.0, 40.0, "m/s"),
    P("wrench_topics", [""], "geometry_msgs/WrenchStamped topics of external forces acting on this vessel, each "
                             "held constant over a step"),
    P("rope_end_topics", [""], "tug_msgs/RopeEndCoupling topics of the rope ends pinned to this vessel (rope "
                               "nodes' end_<a|b>/coupling)"),
    P("contact_topics", [""], "tug_msgs/HullContact topics (hull_contact nodes) this vessel takes part in, as "
                              "fender or hull"),
    P("initial_engine_order", 0.0, "Engine order held from the start, engine already at that rpm (0: the model's "
                                   "own start)", -1.0, 1.0),
    P("initial_steering_angle", 0.0, "Steering angle held from the start, rudder already there (positive to port)",
      -1.6, 1.6, "rad"),
    P("ship_overrides", "", "YAML mapping merged over the ship file, e.g. \"{towline_simple: {enabled: true}}\""),
    P("motion", "", "Prescribed motion instead of dynamics: '' (none), constant_speed, sinusoidal_sway, "
                    "acceleration, turn"),
    P("motion_speed", 0.0, "Prescribed speed U (or U_max for acceleration)", 0.0, 40.0, "m/s"),
    P("motion_amplitude", 0.0, "Sinusoidal sway amplitude", 0.0, 1e3, "m"),
    P("motion_period", 0.0, "Sinusoidal sway period", 0.0, 1e4, "s"),
    P("motion_acceleration", 0.0, "Prescribed acceleration", 0.0, 10.0, "m/s^2"),
    P("motion_turn_rate", 0.0, "Prescribed turn: rate, positive to port", -1.0, 1.0, "rad/s"),
    P("motion_turn_start", 0.0, "Prescribed turn: start time", 0.0, 1e6, "s"),
    P("motion_turn_duration", 0.0, "Prescribed turn: duration", 0.0, 1e6, "s"),
    P("motion_heading", "track", "Heading of a prescribed motion: track (follows the track tangent) or fixed"),
    CURRENT_EAST,
    CURRENT_NORTH,
    P("environment", "", "The run's environment as YAML (a scenario's environment section: wind, current, depth; "
                         "sea_environment.environment); '' = still air, deep water, current_east / current_north"),
    P("marker_rate", 10.0, "Rate of the scene markers (hull, attachments, force arrows; at most the exchange rate)",
      0.1, MARKER_RATE_HI, "Hz", live=True),
    P("marker_force_scale", 1e-4, "Length of the thrust and rope force arrows per newton", 0.0, 1.0, "m/N",
      live=True),
)

# rope_model rope_node: every rope file.
ROPE_NODE = ParamTable(
    "rope_model/rope_node",
    P("rope_file", "table1.yaml", "Rope file: a path, or a file name in share/rope_model/ropes (default: the "
                                  "example rope of Table 1 of Yoon, Lee, Park, Kim, 'Dynamic Modeling and Simulation "
                                  "of a Towing Rope using Multiple Finite Element Method')"),
    P("end_a", "fixed", "End a (tug end, winch end): '<vessel>/<attachment>', 'fixed' or 'free'"),
    P("end_b", "fixed", "End b (tow end): '<vessel>/<attachment>', 'fixed' or 'free'"),
    P("end_a_position", [0.0], "Position [x, y, z] of a fixed or free end a, m, world (map)"),
    P("end_b_position", [0.0], "Position [x, y, z] of a fixed or free end b, m, world (map)"),
    P("layout", "straight", "Initial layout: straight, slack (sagging) or winch (wound on end a)"),
    P("equilibrium", False, "true: settle the laid-out rope to static equilibrium for the ends' step-0 positions "
                            "and velocities before step 0 (not published); false: start from the layout as laid"),
    P("deployed_length", 0.0, "Initial deployed length (slack or winch layouts); 0 = the rope file's length",
      0.0, 1e5, "m"),
    P("n_elements", 0, "Number of elements; 0 = the rope file's", 0, 2000),
    P("max_substep", 0.0, "Largest internal sub-step; 0 = the library default", 0.0, 1.0, "s"),
    P("marker_rate", 10.0, "Rate of the visualization markers (at most the exchange rate)", 0.1, MARKER_RATE_HI,
      "Hz", live=True),
    CURRENT_EAST,
    CURRENT_NORTH,
    P("environment", "", "The run's environment as YAML (a scenario's environment section: wind, current, depth; "
                         "sea_environment.environment), sampled at every element each step; '' = current_east / "
                         "current_north, still air, no seabed"),
)

# hull_contact contact_node. The fender's defaults: a 1 m cylindrical rubber tug fender, reaction
# about 1 MN at 0.5 m compression (linearised 2 MN/m), mu 0.3 (PIANC 2002); hull_contact.fender's
# FenderSpec and the scenario's `contacts` take them from here.
CONTACT_NODE = ParamTable(
    "hull_contact/contact_node",
    P("fender_vessel", "", "Vessel carrying the fender (its namespace)"),
    P("fender", "bow_fender", "The fender point: an attachment of the fender vessel's ship file"),
    P("fender_ship_file", "", "Ship file of the fender vessel (path or name in share/tug_dynamics/ships)"),
    P("fender_ship_overrides", "", "JSON merged over the fender vessel's ship file (as the vessel node's)"),
    P("hull_vessel", "", "Vessel whose hull is pushed on (its namespace)"),
    P("hull_ship_file", "", "Ship file of the hull vessel: its length and beam give the outline"),
    P("hull_ship_overrides", "", "JSON merged over the hull vessel's ship file"),
    P("radius", 0.5, "Fender thickness: its surface ahead of the fender point", 0.0, 10.0, "m"),
    P("stiffness", 2.0e6, "Fender stiffness (linearised reaction)", 1e3, 1e10, "N/m"),
    P("damping", 4.0e5, "Fender damping", 0.0, 1e10, "N s/m"),
    P("friction", 0.3, "Coulomb friction coefficient, fender on hull", 0.0, 2.0),
)

# hull_contact interaction_node: the run's hull interactions, all in one node (Wang's (1975)
# passing-ship loads between pairs, the image-method bank suction; tug_dynamics.interaction_set);
# the scenario's `interactions` set them.
INTERACTION_NODE = ParamTable(
    "hull_contact/interaction_node",
    P("vessels", [""], "The vessels that feel an interaction (their namespaces), in the order of ship_files"),
    P("ship_files", [""], "Ship file of each of `vessels` (path or name in share/tug_dynamics/ships): its length "
                          "and displaced volume give Wang's sectional-area parabola"),
    P("ship_overrides", [""], "JSON merged over each of `vessels`' ship file (as the vessel node's; \"\" none), "
                              "in the same order, or one \"\" for all"),
    P("pairs", [""], "Wang pairs, \"<name>=<vessel a>,<vessel b>\": each vessel feels the other"),
    P("banks", [""], "Banks, \"<name>=<vessel>:x0,y0,x1,y1,...\" (vertical) or \"<name>=<vessel>:<slope>:x0,y0,...\" "
                     "(falling <slope> m across per m down from the line, its waterline): the polyline's points (m, "
                     "world (map)), the water on its left; or \"<name>=<vessel>:depth\": the banks of depth_grid "
                     "across the vessel; the image-method bank suction on the vessel"),
    P("washes", [""], "Propeller wash, \"<name>=<source>,<target>[,<C_w>]\": the source's propeller or "
                      "azimuth-thruster jets on the target's hull side (its thrust from /<source>/thrusters, or "
                      "/<source>/status shared over its propellers), C_w the impingement coefficient 0..1 "
                      "(default 1)"),
    P("depth", 0.0, "Water depth for the bottom images (0: deep water)", 0.0, 1e4, "m"),
    P("depth_grid", "", "ESRI ASCII depth grid (path) whose banks the \"<vessel>:depth\" banks entries feel "
                        "(\"\": none)"),
)

# bridge_instruments nmea_out: NMEA 0183 / AIS over UDP beside a run (the runner sets the lists
# from the scenario's `nmea` key; the scenario's defaults and ranges are these).
NMEA_OUT = ParamTable(
    "bridge_instruments/nmea_out",
    P("vessels", [""], "Every vessel of the run (their namespaces)", read_only=True),
    P("outputs", [""], "Own vessels and where their sentences go: \"vessel@host:port\" (port default "
                       f"{NMEA_UDP_PORT})", read_only=True),
    P("ropes", [""], "The run's ropes as in the scenario: \"rope=<end_a>,<end_b>\"", read_only=True),
    P("ship_files", [""], "\"vessel=path\": the ship files of the AIS dimensions", read_only=True),
    P("scenario", "", "The run's scenario file (path or library name): its vessels' ship files (where ship_files "
                      "names none) and ship_overrides; parameters left at their defaults take its vessels, ropes, "
                      "exchange rate, origin and nmea settings", read_only=True),
    P("mmsi", [""], "\"vessel=244990001\" (default 244990001, 244990002, ... in the order of vessels)",
      read_only=True),
    P("gear_ratios", [""], "\"vessel=5.2\": engine rpm / shaft rpm (default 1)", read_only=True),
    P("rate", 1.0, "sentences per second of simulation time", 0.01, 50.0, "Hz"),
    P("exchange_rate", 50.0, "the run's step rate", 1.0, 1000.0, "Hz"),
    P("origin_latitude", DEFAULT_ORIGIN.latitude, "latitude of the map origin (WGS-84)", -90.0, 90.0, "deg"),
    P("origin_longitude", DEFAULT_ORIGIN.longitude, "longitude of the map origin (WGS-84)", -180.0, 180.0, "deg"),
    P("origin_height", 0.0, "ellipsoid height of the water", -1e3, 1e4, "m"),
    P("utc_start", DEFAULT_UTC_START, "UTC of simulation time 0 (ISO 8601)"),
    P("static_every", 10, "AIS type 5 every n-th report", 1, 100000),
    P("heading_talker", "II", "Talker ID of the heading and rate-of-turn sentences (HDT, ROT); a gyro's is HE, "
                              "which gpsd 3.22 drops (it reads II, GP, HC, IN, TI)", read_only=True),
    P("engine_talker", "II", "Talker ID of the engine and shaft rpm sentences (RPM); the engine room's is ER, "
                             "which gpsd 3.22 drops", read_only=True),
)

# live_view live_view: the Foxglove WebSocket server and the browser instructor station (in the
# runner's process with run_scenario --live, which gives it its topics).
LIVE_VIEW = ParamTable(
    "live_view/live_view",
    P("host", "127.0.0.1", "Address the WebSocket server listens on"),
    P("port", 8765, "WebSocket port (0: any free port)", 0, 65535),
    P("rate", 20.0, "Rate at which new messages go to the clients", 0.5, 200.0, "Hz"),
    P("input_rate", 20.0, "Client orders accepted per second for each kind of client (WebSocket, instructor "
                          "station) and kind of order (vessel command, winch), all connections and addresses "
                          "together; more are refused and counted", 0.1, 1000.0, "1/s", live=True),
    P("max_clients", 32, "Connections at once to the WebSocket server, and to the instructor station (more are "
                         "refused with 503 and counted)", 1, 1000),
    P("allowed_origins", "", "Web pages of other origins allowed to use the WebSocket server and the instructor "
                             "station besides this machine's own (http://localhost, 127.0.0.1 or [::1] with the "
                             "served port), exact, comma-separated, e.g. https://app.foxglove.dev"),
    P("discover", True, "true: serve every topic on the ROS graph of a known type (looked up every 2 s); "
                        "a live view given its topics (run_scenario --live) serves those"),
    P("http_port", 8080, "Port of the browser instructor station (0: any free port, -1: none)", -1, 65535),
    P("http_rate", 10.0, "Rate at which the instructor station samples the simulation (its display period is "
                         "1/rate)", 1.0, 50.0, "Hz"),
    P("particulars", "", "Where the instructor station finds the ropes' breaking loads when no rope node "
                         "answers (a replay): a scenario file (path or library name) or a recording (.mcap, its "
                         "particulars)"),
    P("environment", "", "The run's environment as YAML, as the vessel nodes take it (run_scenario --live passes "
                         "it): the instructor station draws its waves (the same sea, seed and all); '' = taken "
                         "from the scenario `particulars` names (a recording: the scenario it names, beside it or "
                         "in the library), else calm"),
    P("web_root", "", "Folder of the instructor station's page (default: share/live_view/web)"),
)

# Every node's table as it declares it (the stepped nodes: their own, then the stepping ones).
NODE_TABLES = {"vessel_node": VESSEL_NODE + STEPPING, "rope_node": ROPE_NODE + STEPPING,
               "contact_node": CONTACT_NODE + STEPPING,
               "interaction_node": INTERACTION_NODE + STEPPING, "nmea_out": NMEA_OUT, "live_view": LIVE_VIEW}
