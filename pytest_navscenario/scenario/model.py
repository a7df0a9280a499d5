"""Scenario model: frozen dataclasses mirroring the YAML format (version 1).

Fields hold exactly the values written in YAML, in YAML units, so that
``load(dump(s)) == s`` holds bit for bit:

* lengths and positions in metres, times in seconds, speeds in m/s;
* every angle (yaw, field of view, yaw tolerance) in **degrees**, angular rates in deg/s
  and deg/s^2. The simulation and the planner protocol work in radians; convert with
  the ``*_rad`` helpers, never by hand.

Each dataclass is followed by the declaration of its YAML keys (``keys.py``: type, range, unit,
default, one-line description), which the loader, the JSON Schema and the reference page read.
Loading, validation and dumping live in ``loader.py``; this module has no I/O.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, Mapping, Union

from .keys import (REQUIRED, SCENARIO_LIMITS, Choice, Element, Elements, Flag, Integer, Listed, Number, Point, Points,
                   Rows, Rule, Scale, Sub, Text, section)
from .bodies import BODY, Body, PlanarBody
from .terrain import LIDAR3D, Lidar3D, TerrainElement
from .requirements import Requirement, Signal

SCHEMA_VERSION = 1
DRIVES = ("omni", "diff")
SHAPES = ("box", "circle")
REFERENCE_COMPARE = ("time", "path")
MAX_POLYGON_POINTS = 1000
PERSON_RADIUS = 0.25            # m
PERSON_HEIGHT = 1.7             # m
PERSON_SPEED = 1.3              # m/s, a typical walking speed


@dataclass(frozen=True)
class Pose:
    """A planar pose: position in metres, yaw in degrees (counter-clockwise from +x)."""
    x: float
    y: float
    yaw: float = 0.0

    @property
    def yaw_rad(self) -> float:
        return math.radians(self.yaw)


POSE = section(Pose, "pose", "a planar pose", [
    Number("x", "m", "position along x", example="x: 0.0"),
    Number("y", "m", "position along y", example="y: 0.0"),
    Number("yaw", "deg", "heading, counter-clockwise from +x"),
], what="a mapping {x, y, yaw}", home=False)

MOTION_MODES = ("once", "back-and-forth", "loop")


@dataclass(frozen=True)
class Motion:
    """How an obstacle moves (it keeps its orientation). Either along ``path`` (two or more points,
    the first is where it stands until ``start``) at ``speed`` m/s, ``mode`` once (then it stays at
    the last point), back-and-forth or loop (back to the first point and round again); or, with no
    path, at the constant ``velocity`` (m/s, world frame) from its x, y. Times in seconds from the
    episode start. The positions are a pure function of time (scenario/motion.py)."""
    path: tuple[tuple[float, float], ...] = ()
    speed: float = 0.0
    mode: Literal["once", "back-and-forth", "loop"] = "once"
    start: float = 0.0
    velocity: tuple[float, float] | None = None


def _motion_schema(sec: Any, required: list[str]) -> dict[str, Any]:
    """velocity excludes path, speed and mode; without it, the path (and a speed with no
    default) are required."""
    needed = [k for k in ("path", "speed") if k in required]
    for k in needed:
        required.remove(k)
    return {"if": {"required": ["velocity"]},
            "then": {"properties": {"path": False, "speed": False, "mode": False}},
            "else": {"required": needed}}


MOTION = section(Motion, "obstacles[].motion", "how an obstacle moves: along a path, or at a constant velocity", [
    Points("path", "m", "the points [x, y] it walks through; it stands at the first one until start",
           min=2, max=int(SCENARIO_LIMITS["max_obstacles"]), default=REQUIRED,
           example="path: [[0.0, -3.0], [0.0, 3.0]]' or 'velocity: [0.0, 1.0]"),
    Number("speed", "m/s", "its speed along the path", gt=0, default=REQUIRED, example="speed: 1.0"),
    Choice("mode", "", "once: it stays at the last point; back-and-forth; loop: straight back to the "
           "first point and round again", options=MOTION_MODES),
    Number("start", "s", "when it starts moving, in seconds from the episode start", ge=0),
    Point("velocity", "m/s", "instead of a path: a constant velocity [vx, vy] (world frame) from its x, y, "
          "without end", nullable=True),
], what="the obstacle's motion (a mapping)", rules=[
    Rule("'velocity' does not go with 'path', 'speed' or 'mode'; without it, 'path' is required", None,
         _motion_schema),
    Rule("a path has some length (its points are not all the same)", None),
    Rule("no faster than the physics step can follow: it and the robot close in by at most a fifth of their "
         "smallest widths per step (loader.max_resolved_speed)", None),
])


@dataclass(frozen=True)
class BoxObstacle:
    """A static box centred on (x, y): ``length`` along its own x axis, rotated by ``yaw`` degrees."""
    name: str
    x: float
    y: float
    length: float
    width: float
    yaw: float = 0.0
    height: float = 1.0
    motion: Motion | None = None    # None: static
    visible_to_lidar: bool = True   # False: glass, thin wires (it still collides)
    z: float | None = None          # base height (m); None: standing on the ground (terrain)
    kind: Literal["box"] = field(default="box", init=False)

    @property
    def yaw_rad(self) -> float:
        return math.radians(self.yaw)


@dataclass(frozen=True)
class CylinderObstacle:
    """A static upright cylinder centred on (x, y)."""
    name: str
    x: float
    y: float
    radius: float
    height: float = 1.0
    motion: Motion | None = None    # None: static
    visible_to_lidar: bool = True
    z: float | None = None          # base height (m); None: standing on the ground (terrain)
    kind: Literal["cylinder"] = field(default="cylinder", init=False)


@dataclass(frozen=True)
class PolygonObstacle:
    """A prism standing on z = 0: any simple polygon (convex or not) of ``points`` given in the
    obstacle's own frame (metres), placed with that frame's origin at (x, y) and turned by ``yaw``
    degrees, extruded to ``height``."""
    name: str
    x: float
    y: float
    points: tuple[tuple[float, float], ...]
    yaw: float = 0.0
    height: float = 1.0
    motion: Motion | None = None    # None: static
    visible_to_lidar: bool = True
    z: float | None = None          # base height (m); None: standing on the ground (terrain)
    kind: Literal["polygon"] = field(default="polygon", init=False)

    @property
    def yaw_rad(self) -> float:
        return math.radians(self.yaw)


@dataclass(frozen=True)
class MeshObstacle:
    """A triangle mesh read from an STL or OBJ ``file`` beside the scenario (a path relative to the
    scenario file's folder), scaled by ``scale`` (x, y, z), turned by ``yaw`` degrees about z and
    placed with its origin at (x, y) and its lowest point on z = 0. ``footprint`` and ``height`` are
    what the loader read from the file: the outline of the mesh seen from above (in the mesh's own
    frame, scaled) and its height; the simulation and the verdict use them (a prism, see the docs)."""
    name: str
    x: float
    y: float
    file: str
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    yaw: float = 0.0
    footprint: tuple[tuple[float, float], ...] = field(default=(), compare=True)
    height: float = 1.0
    motion: Motion | None = None
    visible_to_lidar: bool = True
    z: float | None = None          # base height (m); None: standing on the ground (terrain)
    kind: Literal["mesh"] = field(default="mesh", init=False)

    @property
    def yaw_rad(self) -> float:
        return math.radians(self.yaw)


_NAME = Text("name", "", "a unique label (generated when absent: box1, cyl1, person1, polygon1, mesh1 ..., "
             "numbered per type in file order)", default=None, name_rules=True,
             default_doc="generated")
_X = Number("x", "m", "where it stands, along x", example="x: 0.0")
_Y = Number("y", "m", "where it stands, along y", example="y: 0.0")
_YAW = Number("yaw", "deg", "its rotation, counter-clockwise")
_HEIGHT = Number("height", "m", "its height, for the 3-D model (below the lidar plane, 0.2 m, it is not "
                 "seen but still collides)", gt=0)
_MOTION = Sub("motion", "", "makes it move (absent: static)", section=MOTION, default=None)
_VISIBLE = Flag("visible_to_lidar", "", "false: the lidar and the safety layer do not see it (glass, "
                "thin wires); the robot still collides with it")
_Z = Number("z", "m", "its base's height above the floor (none: standing on the ground)", nullable=True)


def _placed_by_path(sec: Any, required: list[str]) -> dict[str, Any]:
    """A path's first point is where a moving obstacle stands: no x, y beside it; else the
    x and y without a default are required."""
    needed = [k for k in ("x", "y") if k in required]
    for k in needed:
        required.remove(k)
    return {"if": {"required": ["motion"], "properties": {"motion": {"type": "object", "required": ["path"]}}},
            "then": {"properties": {"x": False, "y": False}},
            "else": {"required": needed} if needed else {}}


_PATH_PLACES = Rule("with a motion path, 'x' and 'y' are not written (the obstacle starts at the "
                    "path's first point)", None, _placed_by_path)
_MAX_OBSTACLES = int(SCENARIO_LIMITS["max_obstacles"])

BOX = section(BoxObstacle, "obstacles[] (box)", "a box centred on (x, y)", [
    _NAME, _X, _Y,
    Number("length", "m", "its size along its own x axis", gt=0, example="length: 1.0"),
    Number("width", "m", "its size across", gt=0, example="width: 1.0"),
    _YAW, _HEIGHT, _MOTION, _VISIBLE, _Z,
], rules=[_PATH_PLACES])
CYLINDER = section(CylinderObstacle, "obstacles[] (cylinder)", "an upright cylinder centred on (x, y)", [
    _NAME, _X, _Y, Number("radius", "m", "its radius", gt=0, example="radius: 0.5"),
    _HEIGHT, _MOTION, _VISIBLE, _Z,
], rules=[_PATH_PLACES])
PERSON = CYLINDER.derive("obstacles[] (person)", "a cylinder with a person's size, walking at 1.3 m/s "
                         "by default; saved (dumped, frozen) as the cylinder it is",
                         defaults={"radius": PERSON_RADIUS, "height": PERSON_HEIGHT},
                         keys={"motion": Sub("motion", "", "makes it move (absent: static)", default=None,
                                             section=MOTION.derive(MOTION.path, MOTION.doc,
                                                                   defaults={"speed": PERSON_SPEED}))})
POLYGON = section(PolygonObstacle, "obstacles[] (polygon)", "a prism on any simple outline, convex or not", [
    _NAME,
    Number("x", "m", "where the points' origin is placed, along x (0: the points are world coordinates)",
           default=0.0),
    Number("y", "m", "where the points' origin is placed, along y", default=0.0),
    Points("points", "m", "three or more corners [x, y] in order around the outline (a closing repeat of "
           "the first is dropped)", min=3, max=MAX_POLYGON_POINTS,
           example="points: [[0, 0], [2, 0], [2, 1], [0, 1]]"),
    _YAW, _HEIGHT, _MOTION, _VISIBLE, _Z,
], rules=[_PATH_PLACES, Rule("a polygon's edges do not cross and it has an area", None)])
MESH = section(MeshObstacle, "obstacles[] (mesh)", "a triangle mesh (.stl or .obj) beside the scenario, "
               "collided as its outline seen from above", [
    _NAME,
    Number("x", "m", "where the mesh's origin is placed, along x", default=0.0),
    Number("y", "m", "where the mesh's origin is placed, along y", default=0.0),
    Text("file", "", "an .stl (binary or ASCII) or .obj file, relative to the scenario's folder and "
         "inside it", path=True, inside=True, example="file: parts/press.stl"),
    Scale("scale", "", "one number for all axes or [sx, sy, sz], e.g. 0.001 for millimetres", le=1000.0,
          default_doc="1"),
    _YAW, _MOTION, _VISIBLE, _Z,
], rules=[_PATH_PLACES, Rule("the mesh file exists, is readable, well-formed and within the size "
                             "limits, and its outline is one piece", None)])

OBSTACLES = Elements("obstacles", "", "the obstacles", max=_MAX_OBSTACLES, what="obstacles", item="obstacle",
                     default=(), example="{type: box, x: 1.0, y: 2.0, length: 1.0, width: 1.0}", types=(
    Element("box", BOX, "box", BOX.doc),
    Element("cylinder", CYLINDER, "cyl", CYLINDER.doc),
    Element("person", PERSON, "person", PERSON.doc),
    Element("polygon", POLYGON, "polygon", POLYGON.doc),
    Element("mesh", MESH, "mesh", MESH.doc),
))


Obstacle = Union[BoxObstacle, CylinderObstacle, PolygonObstacle, MeshObstacle]


@dataclass(frozen=True)
class Footprint:
    """The robot's outline for collisions and distances: a box (length along heading) or a circle."""
    shape: Literal["box", "circle"] = "box"
    length: float = 0.9
    width: float = 0.5
    radius: float = 0.3


def _footprint_keys(values: Mapping[str, Any], given: Any) -> tuple[str, str, str] | None:
    shape = values["shape"]
    for key in ("radius",) if shape == "box" else ("length", "width"):
        if key in given:
            return (key, f"'{key}' does not apply to shape: {shape}",
                    f"remove '{key}'" + (", or set shape: circle" if shape == "box" else ", or set shape: box"))
    return None


FOOTPRINT = section(Footprint, "robot.footprint", "the robot's outline for collisions and distances", [
    Choice("shape", "", "box (length along the heading, width) or circle (radius)", options=SHAPES),
    Number("length", "m", "a box footprint's size along the heading", gt=0),
    Number("width", "m", "a box footprint's size across", gt=0),
    Number("radius", "m", "a circle footprint's radius", gt=0),
], what="the footprint (a mapping)", rules=[
    Rule("a box takes length and width, a circle radius: the other shape's keys are refused", _footprint_keys,
         {"if": {"required": ["shape"], "properties": {"shape": {"const": "circle"}}},
          "then": {"properties": {"length": False, "width": False}},
          "else": {"properties": {"radius": False}}}),
])


@dataclass(frozen=True)
class Limits:
    """Velocity and acceleration limits, enforced by the simulated actuators."""
    max_speed: float = 1.0          # m/s, forward/backward
    max_lateral_speed: float = 0.5  # m/s, sideways (omnidirectional drive only)
    max_yaw_rate: float = 90.0      # deg/s
    max_accel: float = 2.0          # m/s^2
    max_yaw_accel: float = 180.0    # deg/s^2


LIMITS = section(Limits, "robot.limits", "velocity and acceleration limits, enforced by the simulated actuators", [
    Number("max_speed", "m/s", "forward and backward speed limit", gt=0),
    Number("max_lateral_speed", "m/s", "sideways speed limit (omnidirectional drive only)", ge=0),
    Number("max_yaw_rate", "deg/s", "turning rate limit", gt=0),
    Number("max_accel", "m/s²", "acceleration limit", gt=0),
    Number("max_yaw_accel", "deg/s²", "angular acceleration limit", gt=0),
], what="the velocity limits (a mapping)")


@dataclass(frozen=True)
class Lidar:
    """A planar lidar at the robot centre, ray-cast once per control tick."""
    beams: int = 72
    fov: float = 360.0              # degrees, centred on the heading
    range_min: float = 0.05         # m
    range_max: float = 8.0          # m; no return reads as range_max
    noise_sigma: float = 0.0        # m, Gaussian noise on each range
    dropout: float = 0.0            # probability a beam reads as no return
    # a datasheet's noise model (all off by default; see the docs' "sensor faults")
    noise_per_metre: float = 0.0    # m of noise sigma added per metre of range (range-proportional)
    dropout_at_max: float | None = None  # dropout probability at range_max (linear from `dropout` at 0 m)
    spurious: float = 0.0           # probability a beam returns a spurious range short of the true one
    mount_height: float = 0.2       # m above the robot's base (the floor for the planar body): the scan plane

    @property
    def fov_rad(self) -> float:
        return math.radians(self.fov)


def _lidar_range(values: Mapping[str, Any], given: Any) -> tuple[str, str, str] | None:
    if values["range_max"] <= values["range_min"]:
        return ("range_max", f"range_max ({values['range_max']!r} m) must be greater than range_min "
                f"({values['range_min']!r} m)", "raise range_max")
    return None


LIDAR = section(Lidar, "robot.lidar", "a planar lidar at the robot's centre, ray-cast once per control tick", [
    Integer("beams", "", "beams over the field of view", ge=1, le=int(SCENARIO_LIMITS["max_lidar_beams"])),
    Number("fov", "deg", "field of view, centred on the heading", gt=0, le=360.0),
    Number("range_min", "m", "shortest range it reads", ge=0),
    Number("range_max", "m", "longest range; no return reads as range_max", gt=0),
    Number("noise_sigma", "m", "Gaussian noise on each range", ge=0),
    Number("dropout", "", "probability that a beam reads as no return", ge=0, le=1.0),
    Number("noise_per_metre", "m/m", "the noise's sigma grows by this per metre of range", ge=0, le=1.0),
    Number("dropout_at_max", "", "dropout probability at range_max, growing linearly from dropout at 0 m "
           "(none: dropout at every range)", ge=0, le=1.0, nullable=True),
    Number("spurious", "", "probability that a beam returns a spurious range short of the true one", ge=0,
           le=1.0),
    Number("mount_height", "m", "the scan plane's height above the robot's base (the floor for the planar "
           "body)", ge=0, le=10.0),
], what="the lidar settings (a mapping)", rules=[
    Rule("range_max is greater than range_min", _lidar_range),
])


@dataclass(frozen=True)
class Safety:
    """The collision safety layer: halts the robot when its current velocity, held for
    ``horizon`` seconds, would sweep the footprint (grown by ``margin``) into an obstacle."""
    enabled: bool = True
    horizon: float = 0.5            # s
    margin: float = 0.05            # m


SAFETY = section(Safety, "robot.safety", "the collision safety layer", [
    Flag("enabled", "", "the safety layer halts the robot (outcome safety-stop) when its current velocity, "
         "held for horizon, sweeps the footprint grown by margin into an obstacle"),
    Number("horizon", "s", "how long the current velocity is held in the prediction", gt=0),
    Number("margin", "m", "the footprint is grown by this in the prediction", ge=0),
], what="the safety layer settings (a mapping)")


@dataclass(frozen=True)
class Localisation:
    """What the planner believes of the robot's pose: the truth plus an error that is a random walk
    (seeded per episode): its standard deviation grows by ``drift_per_metre`` per square-root
    metre travelled and ``drift_per_second`` per square-root second (so after 1 m, or 1 s, it is
    that much), the heading's by ``yaw_drift_per_metre`` degrees per square-root metre. The
    verdict, the metrics and the pictures use the true pose."""
    drift_per_metre: float = 0.0    # m / sqrt(m)
    drift_per_second: float = 0.0   # m / sqrt(s)
    yaw_drift_per_metre: float = 0.0  # deg / sqrt(m)

    @property
    def drifts(self) -> bool:
        return bool(self.drift_per_metre or self.drift_per_second or self.yaw_drift_per_metre)


LOCALISATION = section(Localisation, "robot.localisation", "the error of the pose the planner is given "
                       "(a seeded random walk)", [
    Number("drift_per_metre", "m/√m", "position error spread after 1 m travelled", ge=0, le=10.0),
    Number("drift_per_second", "m/√s", "position error spread after 1 s", ge=0, le=10.0),
    Number("yaw_drift_per_metre", "deg/√m", "heading error spread after 1 m travelled", ge=0, le=90.0),
], what="the localisation error (a mapping)")


@dataclass(frozen=True)
class Latency:
    """Delays, in seconds, whole multiples of the control period: the planner sees observations
    ``observation`` seconds old; its commands take effect ``command`` seconds after it answered."""
    observation: float = 0.0
    command: float = 0.0


LATENCY = section(Latency, "robot.latency", "delays, whole multiples of the control period", [
    Number("observation", "s", "the planner sees observations this old", ge=0, le=10.0),
    Number("command", "s", "the planner's commands act this much later", ge=0, le=10.0),
], what="the delays (a mapping)")


@dataclass(frozen=True)
class Robot:
    footprint: Footprint = Footprint()
    drive: Literal["omni", "diff"] = "omni"
    limits: Limits = Limits()
    lidar: Lidar = Lidar()
    safety: Safety = Safety()
    localisation: Localisation = Localisation()
    latency: Latency = Latency()
    body: Body = PlanarBody()       # how the robot meets the ground (scenario/bodies/)
    lidar3d: Lidar3D | None = None  # a multi-ring lidar, off by default


ROBOT = section(Robot, "robot", "the robot: its outline, drive, limits, sensor and faults", [
    Sub("footprint", "", "the outline used for collisions and distances", section=FOOTPRINT),
    Choice("drive", "", "omni: commands (vx, vy, wz); diff: (v, wz)", options=DRIVES),
    Sub("limits", "", "velocity and acceleration limits", section=LIMITS),
    Sub("lidar", "", "the planar lidar", section=LIDAR),
    Sub("safety", "", "the collision safety layer", section=SAFETY),
    Sub("localisation", "", "the planner's localisation error", section=LOCALISATION),
    Sub("latency", "", "observation and command delays", section=LATENCY),
    BODY,
    Sub("lidar3d", "", "a multi-ring 3D lidar (absent: none; {} for one with the defaults)", section=LIDAR3D,
        default=None),
], what="the robot settings (a mapping)")


@dataclass(frozen=True)
class GoalTolerance:
    position: float = 0.3           # m
    yaw: float | None = None        # degrees; None = heading at the goal is not checked


GOAL_TOLERANCE = section(GoalTolerance, "mission.goal_tolerance", "when the goal counts as reached", [
    Number("position", "m", "distance to the goal that counts as reached", gt=0),
    Number("yaw", "deg", "heading tolerance at the goal (none: the heading is not checked)", gt=0, le=180.0,
           nullable=True),
], what="the goal tolerance (a mapping {position, yaw})")


@dataclass(frozen=True)
class Mission:
    """Drive from ``start`` through ``waypoints`` (in order) to ``goal`` before ``timeout``."""
    start: Pose
    goal: Pose
    waypoints: tuple[Pose, ...] = ()
    goal_tolerance: GoalTolerance = GoalTolerance()
    waypoint_tolerance: float = 0.5  # m: a waypoint counts as passed within this distance
    timeout: float = 30.0            # s


MISSION = section(Mission, "mission", "drive from start through the waypoints to the goal before the timeout", [
    Sub("start", "m, deg", "where the robot starts {x, y, yaw}; its footprint there must not touch an "
        "obstacle", section=POSE, nullable=False, example="start: {x: 0.0, y: 0.0, yaw: 90.0}"),
    Sub("goal", "m, deg", "where it must go {x, y, yaw}; its footprint there must not touch a static "
        "obstacle", section=POSE, nullable=False, example="goal: {x: 0.0, y: 0.0, yaw: 90.0}"),
    Listed("waypoints", "m, deg", "poses {x, y[, yaw]} passed in order; none may lie inside an obstacle",
           section=POSE, max=int(SCENARIO_LIMITS["max_waypoints"]), what="waypoints"),
    Sub("goal_tolerance", "", "when the goal counts as reached", section=GOAL_TOLERANCE),
    Number("waypoint_tolerance", "m", "a waypoint counts as passed within this distance", gt=0),
    Number("timeout", "s", "the episode ends unsuccessfully after this", gt=0),
], what="the mission (a mapping)")


@dataclass(frozen=True)
class Perturb:
    """Opt-in randomness of the episode beyond its sensors (all off by default): each episode draws,
    from its noise seed, a start pose up to ``start_xy`` metres away from the mission's start along
    each axis and ``start_yaw`` degrees off its heading, and shifts each moving obstacle's start
    time by up to ``motion_time`` seconds earlier or later (never before 0), all uniform. A start
    drawn onto an obstacle is drawn nearer (scenario/perturb.py)."""
    start_xy: float = 0.0           # m
    start_yaw: float = 0.0          # deg
    motion_time: float = 0.0        # s

    @property
    def any(self) -> bool:
        return bool(self.start_xy or self.start_yaw or self.motion_time)


PERTURB = section(Perturb, "simulation.perturb", "small random changes of each episode, drawn from its noise "
                  "seed: the start pose and moving obstacles' timing", [
    Number("start_xy", "m", "the start moves by up to this along x and along y (uniform)", ge=0, le=1.0),
    Number("start_yaw", "deg", "the start heading turns by up to this either way (uniform)", ge=0, le=45.0),
    Number("motion_time", "s", "each moving obstacle starts up to this much earlier or later (uniform, never "
           "before 0)", ge=0, le=10.0),
], what="the perturbation (a mapping)")


@dataclass(frozen=True)
class Simulation:
    timestep: float = 0.01          # s, physics step
    control_rate: float = 10.0      # Hz, planner ticks; must divide 1/timestep into whole steps
    seed: int = 0                   # noise seed of the episode (the run's base seed is mixed in)
    perturb: Perturb = Perturb()    # opt-in: the start pose and moving obstacles' timing vary per episode


SIMULATION = section(Simulation, "simulation", "the physics step, the planner's rate and the noise seed", [
    Number("timestep", "s", "the physics step", gt=0, le=1.0),
    Number("control_rate", "Hz", "planner ticks per second; 1 / (timestep × control_rate) must be a whole "
           "number of physics steps", gt=0, le=1000.0),
    Integer("seed", "", "the episode's noise seed (the run's base seed is mixed in)", ge=0, le=2**63 - 1),
    Sub("perturb", "", "small random changes of each episode: start pose, moving obstacles' timing (absent: "
        "none)", section=PERTURB),
], what="the simulation settings (a mapping)")


def randomness(scenario: "Scenario") -> tuple[str, ...]:
    """What in ``scenario`` changes with the episode's noise seed (empty: every run of it is the
    same, for a deterministic planner): the lidar's noise, dropout and spurious returns, the
    localisation drift, and the opt-in perturbations of ``simulation.perturb``."""
    lid, loc, per = scenario.robot.lidar, scenario.robot.localisation, scenario.simulation.perturb
    out = []
    if lid.noise_sigma or lid.noise_per_metre:
        out.append("lidar noise")
    if lid.dropout or lid.dropout_at_max:
        out.append("lidar dropout")
    if lid.spurious:
        out.append("spurious returns")
    if loc.drifts:
        out.append("localisation drift")
    if per.start_xy or per.start_yaw:
        out.append("start perturbation")
    if per.motion_time and any(getattr(o, "motion", None) is not None for o in scenario.obstacles):
        out.append("timing perturbation")
    return tuple(out)


@dataclass(frozen=True)
class Mark:
    """A pytest mark from YAML: ``slow``, ``{xfail: {reason: ...}}``, ``{skip: reason}``."""
    name: str
    args: tuple[Any, ...] = ()
    kwargs: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Reference:
    """A recorded trajectory to compare the simulated run with (from a bag or a CSV).

    ``file`` is relative to the scenario file; ``points`` are (t, x, y) rows given inline;
    ``compare`` says what the reference deviation metrics measure (see verdict/metrics.py).
    """
    file: str | None = None
    points: tuple[tuple[float, float, float], ...] = ()
    compare: Literal["time", "path"] = "time"   # time: at the same times; path: the same way, whatever the pace


def _one_source(values: Mapping[str, Any], given: Any) -> tuple[str, str, str] | None:
    if ("file" in given) == ("points" in given):
        return ("", "give exactly one of 'file' or 'points'",
                "file: path/to/trajectory.csv (relative to this file), or points: [[t, x, y], ...]")
    return None


REFERENCE = section(Reference, "reference", "a recorded trajectory to compare the run with", [
    Text("file", "", "a CSV or bag file, relative to the scenario file", path=True, default=None),
    Rows("points", "s, m, m", "rows [t, x, y] given inline, t strictly increasing", columns=("t", "x", "y"),
         max=int(SCENARIO_LIMITS["max_reference_points"])),
    Choice("compare", "", "time: the run at the same times; path: where both went, whatever the pace",
           options=REFERENCE_COMPARE),
], what="the reference trajectory (a mapping {file | points})", rules=[
    Rule("exactly one of 'file' or 'points'", _one_source,
         {"oneOf": [{"required": ["file"]}, {"required": ["points"]}]}),
    Rule("the reference points' times increase strictly", None),
])


@dataclass(frozen=True)
class Scenario:
    mission: Mission
    obstacles: tuple[Obstacle, ...] = ()
    robot: Robot = Robot()
    simulation: Simulation = Simulation()
    version: int = SCHEMA_VERSION
    name: str = ""                  # defaults to the file stem
    family: str = ""                # defaults to the parent folder name
    description: str = ""
    marks: tuple[Mark, ...] = ()
    reference: Reference | None = None
    search: Mapping[str, Any] | None = None      # search-space overrides (search.py validates)
    provenance: Mapping[str, Any] | None = None  # written by freeze.py: where a frozen failure came from
    terrain: tuple[TerrainElement, ...] = ()     # ground that is not the flat floor (scenario/terrain/)
    signals: tuple[Signal, ...] = ()             # declared signals (scenario/requirements.py)
    requirements: tuple[Requirement, ...] = ()   # STL rules every episode is checked against
    # Where it was loaded from (not part of the content, not dumped): for errors and relative paths.
    source: str | None = field(default=None, compare=False, repr=False)

    def obstacle(self, name: str) -> Obstacle:
        for obs in self.obstacles:
            if obs.name == name:
                return obs
        raise KeyError(name)


# requirements and their signals judge an episode, they are not what the robot experiences
_NOT_CONTENT = {"name", "family", "description", "marks", "provenance", "source", "search", "signals",
                "requirements"}
# Fields added after scenarios were first hashed: at their default they are left out of the hash,
# so a file written before them keeps its hash (results files pair scenarios by it).
_ADDED_DEFAULTS: dict[str, Any] = {"noise_per_metre": 0.0, "dropout_at_max": None, "spurious": 0.0,
                                   "localisation": Localisation(), "latency": Latency(),
                                   # terrain (scenario/terrain/): field names unique to what they mean
                                   "z": None, "mount_height": 0.2, "body": PlanarBody(), "lidar3d": None,
                                   "terrain": (), "perturb": Perturb(), "com_height": None,
                                   # an mjcf body's declared limits (a legged body's are never None)
                                   "max_step": None, "max_slope": None, "max_gap": None}


_CONTENT_FIELDS: dict[type, tuple[tuple[str, bool], ...]] = {}   # dataclass -> (field, added later?)


def _content_fields(cls: type) -> tuple[tuple[str, bool], ...] | None:
    """The hashed fields of a dataclass type (None for other types), worked out once per type."""
    try:
        return _CONTENT_FIELDS[cls]
    except KeyError:
        pass
    import dataclasses
    fields = None
    if dataclasses.is_dataclass(cls):
        fields = tuple((f.name, f.name in _ADDED_DEFAULTS) for f in dataclasses.fields(cls)
                       if f.name not in _NOT_CONTENT)
    _CONTENT_FIELDS[cls] = fields
    return fields


def _plain(value: Any) -> Any:
    """content_hash's JSON body of a value: dataclasses as dicts of their content fields, numbers
    as the repr of their float (exact; 1 and 1.0 hash alike)."""
    cls = type(value)
    if cls is float or cls is int:
        return repr(float(value))
    if cls is str or value is None or cls is bool:
        return value
    fields = _content_fields(cls)
    if fields is not None:
        out = {}
        for name, added in fields:
            item = getattr(value, name)
            if added and item == _ADDED_DEFAULTS[name]:
                continue
            out[name] = _plain(item)
        return out
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return repr(float(value))
    return value


def content_hash(scenario: Scenario) -> str:
    """A stable 16-hex-digit hash of what the robot experiences (robot, mission, obstacles,
    simulation, reference), ignoring names, marks, provenance and search settings.

    Used to pair scenarios across result files and to name frozen failures, so the same
    layout found twice gets the same name.
    """
    import hashlib
    import json

    body = _plain(scenario)
    # obstacle names are labels, not content
    for obs in body.get("obstacles", []):
        obs.pop("name", None)
        if obs.get("motion") is None:   # a static obstacle hashes as before motion existed
            obs.pop("motion", None)
        obs.pop("file", None)           # a mesh is its outline and height (hashed), wherever its file is
        if obs.get("visible_to_lidar", True) is True:    # the default hashes as before it existed
            obs.pop("visible_to_lidar", None)
    for element in body.get("terrain", []):   # terrain names are labels; a heightfield is its digest
        element.pop("name", None)
        element.pop("file", None)
    robot_body = body.get("robot", {}).get("body")
    if isinstance(robot_body, dict) and robot_body.get("kind") == "mjcf":
        robot_body.pop("file", None)            # an MJCF body is its digest, wherever its file is
    text = json.dumps(body, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]
