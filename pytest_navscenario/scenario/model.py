"""Scenario model: frozen dataclasses mirroring the YAML format (version 1).

Fields hold exactly the values written in YAML, in YAML units, so that
``load(dump(s)) == s`` holds bit for bit:

* lengths and positions in metres, times in seconds, speeds in m/s;
* every angle (yaw, field of view, yaw tolerance) in **degrees**, angular rates in deg/s
  and deg/s^2. The simulation and the planner protocol work in radians; convert with
  the ``*_rad`` helpers, never by hand.

Loading, validation and dumping live in ``loader.py``; this module has no I/O.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, Mapping, Union

from .terrain import Body, Lidar3D, PlanarBody, TerrainElement

SCHEMA_VERSION = 1


@dataclass(frozen=True)
class Pose:
    """A planar pose: position in metres, yaw in degrees (counter-clockwise from +x)."""
    x: float
    y: float
    yaw: float = 0.0

    @property
    def yaw_rad(self) -> float:
        return math.radians(self.yaw)


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


Obstacle = Union[BoxObstacle, CylinderObstacle, PolygonObstacle, MeshObstacle]


@dataclass(frozen=True)
class Footprint:
    """The robot's outline for collisions and distances: a box (length along heading) or a circle."""
    shape: Literal["box", "circle"] = "box"
    length: float = 0.9
    width: float = 0.5
    radius: float = 0.3


@dataclass(frozen=True)
class Limits:
    """Velocity and acceleration limits, enforced by the simulated actuators."""
    max_speed: float = 1.0          # m/s, forward/backward
    max_lateral_speed: float = 0.5  # m/s, sideways (omnidirectional drive only)
    max_yaw_rate: float = 90.0      # deg/s
    max_accel: float = 2.0          # m/s^2
    max_yaw_accel: float = 180.0    # deg/s^2


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


@dataclass(frozen=True)
class Safety:
    """The collision safety layer: halts the robot when its current velocity, held for
    ``horizon`` seconds, would sweep the footprint (grown by ``margin``) into an obstacle."""
    enabled: bool = True
    horizon: float = 0.5            # s
    margin: float = 0.05            # m


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


@dataclass(frozen=True)
class Latency:
    """Delays, in seconds, whole multiples of the control period: the planner sees observations
    ``observation`` seconds old; its commands take effect ``command`` seconds after it answered."""
    observation: float = 0.0
    command: float = 0.0


@dataclass(frozen=True)
class Robot:
    footprint: Footprint = Footprint()
    drive: Literal["omni", "diff"] = "omni"
    limits: Limits = Limits()
    lidar: Lidar = Lidar()
    safety: Safety = Safety()
    localisation: Localisation = Localisation()
    latency: Latency = Latency()
    body: Body = PlanarBody()       # how the robot meets the ground (scenario/terrain.py)
    lidar3d: Lidar3D | None = None  # a multi-ring lidar, off by default


@dataclass(frozen=True)
class GoalTolerance:
    position: float = 0.3           # m
    yaw: float | None = None        # degrees; None = heading at the goal is not checked


@dataclass(frozen=True)
class Mission:
    """Drive from ``start`` through ``waypoints`` (in order) to ``goal`` before ``timeout``."""
    start: Pose
    goal: Pose
    waypoints: tuple[Pose, ...] = ()
    goal_tolerance: GoalTolerance = GoalTolerance()
    waypoint_tolerance: float = 0.5  # m: a waypoint counts as passed within this distance
    timeout: float = 30.0            # s


@dataclass(frozen=True)
class Simulation:
    timestep: float = 0.01          # s, physics step
    control_rate: float = 10.0      # Hz, planner ticks; must divide 1/timestep into whole steps
    seed: int = 0                   # noise seed of the episode (the run's base seed is mixed in)


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
    terrain: tuple[TerrainElement, ...] = ()     # ground that is not the flat floor (scenario/terrain.py)
    # Where it was loaded from (not part of the content, not dumped): for errors and relative paths.
    source: str | None = field(default=None, compare=False, repr=False)

    def obstacle(self, name: str) -> Obstacle:
        for obs in self.obstacles:
            if obs.name == name:
                return obs
        raise KeyError(name)


_NOT_CONTENT = {"name", "family", "description", "marks", "provenance", "source", "search"}
# Fields added after scenarios were first hashed: at their default they are left out of the hash,
# so a file written before them keeps its hash (results files pair scenarios by it).
_ADDED_DEFAULTS: dict[str, Any] = {"noise_per_metre": 0.0, "dropout_at_max": None, "spurious": 0.0,
                                   "localisation": Localisation(), "latency": Latency(),
                                   # terrain (scenario/terrain.py): field names unique to what they mean
                                   "z": None, "mount_height": 0.2, "body": PlanarBody(), "lidar3d": None,
                                   "terrain": ()}


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
    text = json.dumps(body, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]
