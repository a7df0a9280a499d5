"""The obstacles of a scenario: frozen dataclasses (box, cylinder, polygon, mesh; a person is a
cylinder with a person's size) and how one moves (``Motion``), each followed by the declaration of
its YAML keys (``keys.py``), in YAML units (metres, degrees, seconds). Part of the model
(``model.py`` re-exports every name); no I/O: a mesh's outline is read by the loader.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, Union

from .keys import REQUIRED, SCENARIO_LIMITS, Choice, Element, Elements, Flag, Number, Point, Points, Rule, Scale, Sub, Text, section

MAX_POLYGON_POINTS = 1000
PERSON_RADIUS = 0.25            # m
PERSON_HEIGHT = 1.7             # m
PERSON_SPEED = 1.3              # m/s, a typical walking speed

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
