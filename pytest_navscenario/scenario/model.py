"""Scenario model: frozen dataclasses mirroring the YAML format (version 1).

Fields hold exactly the values written in YAML, in YAML units, so that
``load(dump(s)) == s`` holds bit for bit:

* lengths and positions in metres, times in seconds, speeds in m/s;
* every angle (yaw, field of view, yaw tolerance) in **degrees**, angular rates in deg/s
  and deg/s^2. The simulation and the planner protocol work in radians; convert with
  the ``*_rad`` helpers, never by hand.

Each dataclass is followed by the declaration of its YAML keys (``keys.py``: type, range, unit,
default, one-line description), which the loader, the JSON Schema and the reference page read.
This module holds the pose, the mission, the simulation settings, the marks, the reference, the
top-level ``Scenario`` and its ``content_hash``; the obstacles are in ``obstacles.py`` and the robot
in ``robot.py`` (every name re-exported here). Loading, validation and dumping live in
``loader.py``; this module has no I/O.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, Mapping

from .keys import SCENARIO_LIMITS, Choice, Integer, Listed, Number, Rows, Rule, Sub, Text, section
from .obstacles import (  # noqa: F401  (the obstacles are part of the model: re-exported)
    BOX,
    CYLINDER,
    MAX_POLYGON_POINTS,
    MESH,
    MOTION,
    MOTION_MODES,
    OBSTACLES,
    PERSON,
    PERSON_HEIGHT,
    PERSON_RADIUS,
    PERSON_SPEED,
    POLYGON,
    BoxObstacle,
    CylinderObstacle,
    MeshObstacle,
    Motion,
    Obstacle,
    PolygonObstacle,
)
from .robot import (  # noqa: F401  (the robot is part of the model: re-exported)
    DRIVES,
    FOOTPRINT,
    LATENCY,
    LIDAR,
    LIMITS,
    LOCALISATION,
    ROBOT,
    SAFETY,
    SHAPES,
    Footprint,
    Latency,
    Lidar,
    Limits,
    Localisation,
    Robot,
    Safety,
)
from .bodies import BODY, Body, PlanarBody  # noqa: F401  (re-exported)
from .terrain import LIDAR3D, Lidar3D, TerrainElement  # noqa: F401  (re-exported)
from .requirements import Requirement, Signal

SCHEMA_VERSION = 1
REFERENCE_COMPARE = ("time", "path")


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
