"""Terrain, bodies and the 3D lidar: the scenario-model side of ground that is not a flat floor.

Frozen dataclasses mirroring the YAML, in YAML units (metres, degrees), like ``model.py``; no I/O.
Three additions to a scenario, each off by default so that every file written before them loads
and means the same, bit for bit (and hashes the same: see ``model._ADDED_DEFAULTS``):

* ``terrain:`` a list of elements, each placed like an obstacle by its footprint centre (x, y) and
  ``yaw`` (degrees, counter-clockwise), its own +x axis being the direction it rises or runs along.
  Raised elements (ramp, steps, platform) and patches (rough, heightfield) rest their base at ``z``
  metres above the floor (0 by default: on the floor); a pit is a hole in the floor. The floor
  elsewhere is z = 0, as today.
* ``robot.body``: how the robot meets the ground. ``planar`` (the default) is today's body: slide
  and hinge joints in the plane, gravity off. ``wheeled`` rides the terrain under gravity on real
  wheel contacts; ``legged`` is a capability model of a walking robot (what it can climb, step over
  and cross), not a walking controller; ``mjcf`` is the user's own MJCF robot with a controller of
  theirs. ``robot.drive`` (omni, diff) still says what the planner's commands mean.
* ``robot.lidar3d``: a spinning multi-ring lidar whose point cloud is part of the observation; the
  2D lidar (``robot.lidar``) stays, at its ``mount_height`` above the robot's base.

Names (``name``) label elements in messages ("fell off platform 'dock'"); they are not content.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, Union

from .keys import SCENARIO_LIMITS as _LIMITS
from .keys import Choice, Element, Elements, Integer, Number, Rule, Text, Variant, section

# ---------------------------------------------------------------- terrain elements


@dataclass(frozen=True)
class Ramp:
    """An inclined plane ``length`` long (along its own +x) and ``width`` wide, rising by ``rise``
    from its low end (at -x, height ``z``) to its high end (at +x, height ``z + rise``); solid
    below its surface, with vertical sides."""
    name: str
    x: float
    y: float
    length: float
    width: float
    rise: float
    yaw: float = 0.0
    z: float = 0.0
    kind: Literal["ramp"] = field(default="ramp", init=False)

    @property
    def slope(self) -> float:
        """The ramp's slope in degrees."""
        return math.degrees(math.atan2(self.rise, self.length))


@dataclass(frozen=True)
class Steps:
    """A flight of ``count`` steps, each ``rise`` high and ``run`` deep, ``width`` wide, over a
    footprint ``count * run`` long centred on (x, y). ``up``: they climb along their own +x from
    the base height ``z`` (the top of the last step at ``z + count * rise``). ``down``: they descend
    along +x below ``z``, cut into the ground (the last step's top at ``z - count * rise``), as a
    stairwell seen from the floor above."""
    name: str
    x: float
    y: float
    count: int
    rise: float
    run: float
    width: float
    yaw: float = 0.0
    z: float = 0.0
    direction: Literal["up", "down"] = "up"
    kind: Literal["steps"] = field(default="steps", init=False)

    @property
    def length(self) -> float:
        return self.count * self.run


@dataclass(frozen=True)
class Platform:
    """A raised floor (a loading dock, a mezzanine): a solid block ``length`` by ``width`` whose top
    is ``height`` above its base ``z``, with drop edges on every side."""
    name: str
    x: float
    y: float
    length: float
    width: float
    height: float
    yaw: float = 0.0
    z: float = 0.0
    kind: Literal["platform"] = field(default="platform", init=False)


@dataclass(frozen=True)
class Pit:
    """A hole in the floor, ``length`` by ``width``, ``depth`` deep, with vertical walls."""
    name: str
    x: float
    y: float
    length: float
    width: float
    depth: float
    yaw: float = 0.0
    kind: Literal["pit"] = field(default="pit", init=False)


@dataclass(frozen=True)
class Rough:
    """A patch of rough ground ``length`` by ``width``: smooth random bumps of up to ``amplitude``
    metres with a typical spacing of ``wavelength`` metres, drawn from ``seed`` (the same seed gives
    the same ground), resting on ``z``."""
    name: str
    x: float
    y: float
    length: float
    width: float
    amplitude: float
    wavelength: float
    seed: int = 0
    yaw: float = 0.0
    z: float = 0.0
    kind: Literal["rough"] = field(default="rough", init=False)


@dataclass(frozen=True)
class Heightfield:
    """A height grid read from ``file`` beside the scenario (a greyscale PNG or a NumPy ``.npy``
    array; the same path rules as mesh obstacles), stretched over ``length`` by ``width`` metres,
    its values mapped to heights from ``min_height`` to ``max_height`` above ``z``. ``digest`` is
    what the loader read from the file (a hash of the grid): it makes the grid part of the content,
    wherever the file lives."""
    name: str
    x: float
    y: float
    file: str
    length: float
    width: float
    min_height: float = 0.0
    max_height: float = 1.0
    yaw: float = 0.0
    z: float = 0.0
    digest: str = ""
    kind: Literal["heightfield"] = field(default="heightfield", init=False)


TerrainElement = Union[Ramp, Steps, Platform, Pit, Rough, Heightfield]
TERRAIN_TYPES = ("ramp", "steps", "platform", "pit", "rough", "heightfield")


# ---------------------------------------------------------------- bodies


@dataclass(frozen=True)
class PlanarBody:
    """Today's body: a rigid box or disc (the footprint) on planar joints with gravity off. It
    never leaves z = 0; it cannot climb, fall or tip."""
    kind: Literal["planar"] = field(default="planar", init=False)


@dataclass(frozen=True)
class WheeledBody:
    """A wheeled robot riding the terrain under gravity on real wheel contacts: ``diff`` has two
    driven wheels on one axle and passive casters, ``skid`` four driven wheels (skid-steer). A
    low-level controller in the harness turns the planner's velocity command into wheel torques
    within ``max_wheel_torque`` (N m per wheel) and ``max_wheel_speed`` (rad/s; None: the speed
    that gives limits.max_speed). ``track`` (lateral wheel spacing) and ``wheelbase`` (skid: axle
    spacing) default to the footprint's size (the wheels inside it); the mass centre sits
    ``com_height`` above the ground (None: at the wheels' axle). The robot counts as tipped over when
    its roll or pitch passes ``tip_angle`` degrees (scenario/ground/chassis.py: the layout)."""
    drive_wheels: Literal["diff", "skid"] = "diff"
    wheel_radius: float = 0.1            # m
    wheel_width: float = 0.05            # m
    track: float | None = None           # m; None: the footprint's width less wheel_width (wheels inside it)
    wheelbase: float | None = None       # m, skid only; None: 0.6 x the footprint's length
    mass: float = 50.0                   # kg, chassis and wheels
    max_wheel_torque: float = 10.0       # N m per driven wheel
    max_wheel_speed: float | None = None  # rad/s; None: limits.max_speed / wheel_radius
    clearance: float = 0.1               # m, chassis underside above the ground on a flat floor (0.05 with a
                                         # 0.9 m footprint: a 6 deg approach angle, no 10 deg ramp)
    tip_angle: float = 45.0              # degrees of roll or pitch that count as tipped over
    com_height: float | None = None      # m, the mass centre above the ground; None: the wheels' axle
    kind: Literal["wheeled"] = field(default="wheeled", init=False)


@dataclass(frozen=True)
class LeggedBody:
    """A walking robot (an ANYmal) declared by what it can do, not how it walks: it climbs steps up
    to ``max_step`` metres, slopes up to ``max_slope`` degrees, crosses gaps up to ``max_gap``
    metres and carries its body ``clearance`` metres above the ground. A capability model: the body
    follows the ground it can cross and is stopped (or falls) where it cannot; no legs, feet or gait
    are simulated."""
    max_step: float = 0.2                # m
    max_slope: float = 30.0              # degrees
    max_gap: float = 0.3                 # m
    clearance: float = 0.35              # m, body underside above the ground
    tip_angle: float = 45.0              # degrees of roll or pitch that count as tipped over
    kind: Literal["legged"] = field(default="legged", init=False)


@dataclass(frozen=True)
class MjcfBody:
    """The user's own robot: an MJCF ``file`` beside the scenario (same path rules as meshes) whose
    ``base`` body (None: the first body with a free joint) is the robot, driven by ``controller``
    (``pkg.mod:Attr``, loaded like a subject), which turns each velocity command into the model's
    actuator controls. ``digest`` is what the loader read from the file (a hash of its bytes): it
    makes the model part of the content, wherever the file lives (with every file MuJoCo opens
    for it: scenario/mjcf_files.robot_digest). What it can cross is the user's to declare (the harness cannot estimate it from an
    arbitrary model): ``max_step`` and ``max_slope`` together, and ``max_gap`` (None: no gap), and the
    path search and the feasibility check then treat it as a legged body's limits
    (scenario/ground/crossing.py); undeclared, they ignore the terrain for it."""
    file: str
    controller: str
    base: str | None = None
    tip_angle: float = 45.0              # degrees of roll or pitch that count as tipped over
    max_step: float | None = None        # m, the highest step it climbs (None: undeclared)
    max_slope: float | None = None       # degrees, the steepest slope it drives (with max_step)
    max_gap: float | None = None         # m, the widest gap it crosses (None: none)
    digest: str = ""                     # what the loader read from the file (a hash of its bytes)
    kind: Literal["mjcf"] = field(default="mjcf", init=False)


Body = Union[PlanarBody, WheeledBody, LeggedBody, MjcfBody]
BODY_TYPES = ("planar", "wheeled", "legged", "mjcf")


# ---------------------------------------------------------------- the 3D lidar


@dataclass(frozen=True)
class Lidar3D:
    """A spinning multi-ring lidar (defaults like a 16-ring unit): ``rings`` rings spread evenly
    from ``fov_low`` to ``fov_high`` degrees of elevation, ``beams`` beams per ring over 360
    degrees, mounted at (``mount_x``, ``mount_y``, ``mount_z``) on the robot's base, tilted by
    ``mount_pitch`` degrees (positive: looking down). Its points (N x 3, sensor frame) are part of
    the observation. The noise, dropout and spurious-return models are the 2D lidar's."""
    rings: int = 16
    beams: int = 360
    fov_low: float = -15.0               # degrees
    fov_high: float = 15.0               # degrees
    range_min: float = 0.3               # m
    range_max: float = 30.0              # m
    mount_x: float = 0.0                 # m, robot frame
    mount_y: float = 0.0
    mount_z: float = 0.5                 # m above the base's origin
    mount_pitch: float = 0.0             # degrees, positive looks down
    noise_sigma: float = 0.0
    dropout: float = 0.0
    noise_per_metre: float = 0.0
    dropout_at_max: float | None = None
    spurious: float = 0.0


# ---------------------------------------------------------------- YAML keys (scenario/keys.py form)
# The declarations the loader, the JSON Schema and the reference page read. Ranges are the format's
# limits; what an element means for the simulation is the terrain modules' business.

_NAME = Text("name", "", "a label for messages (generated when absent: ramp1, steps1 ...)", default=None,
             name_rules=True, default_doc="generated")
_X = Number("x", "m", "its footprint's centre, along x", example="x: 0.0")
_Y = Number("y", "m", "its footprint's centre, along y", example="y: 0.0")
_LENGTH = Number("length", "m", "its size along its own x axis (the way it rises or runs)", gt=0,
                 example="length: 2.0")
_WIDTH = Number("width", "m", "its size across", gt=0, example="width: 1.0")
_YAW = Number("yaw", "deg", "its rotation, counter-clockwise")
_Z = Number("z", "m", "the height of its base above the floor", ge=0)
_SEED = Integer("seed", "", "the random seed of its shape (the same seed, the same ground)", ge=0, le=2**63 - 1)


def _heights(values: Any, given: Any) -> tuple[str, str, str] | None:
    if values["max_height"] <= values["min_height"]:
        return ("max_height", f"max_height ({values['max_height']!r} m) must be greater than min_height "
                f"({values['min_height']!r} m)", "raise max_height")
    return None


RAMP = section(Ramp, "terrain[] (ramp)", "an inclined plane rising by rise along its own +x", [
    _NAME, _X, _Y, _LENGTH, _WIDTH,
    Number("rise", "m", "how much its high end (+x) is above its low end", gt=0, example="rise: 0.3"),
    _YAW, _Z])
STEPS = section(Steps, "terrain[] (steps)", "a flight of steps, count × run long", [
    _NAME, _X, _Y,
    Integer("count", "", "how many steps", ge=1, le=1000, example="count: 3"),
    Number("rise", "m", "each step's height", gt=0, example="rise: 0.15"),
    Number("run", "m", "each step's depth", gt=0, example="run: 0.3"),
    _WIDTH, _YAW, _Z,
    Choice("direction", "", "up: they climb along +x from z; down: they descend along +x below z, cut into "
           "the ground", options=("up", "down"))])
PLATFORM = section(Platform, "terrain[] (platform)", "a raised floor with drop edges on every side", [
    _NAME, _X, _Y, _LENGTH, _WIDTH,
    Number("height", "m", "its top above its base z", gt=0, example="height: 1.0"), _YAW, _Z])
PIT = section(Pit, "terrain[] (pit)", "a hole in the floor with vertical walls", [
    _NAME, _X, _Y, _LENGTH, _WIDTH, Number("depth", "m", "how deep it is", gt=0, example="depth: 0.5"), _YAW])
ROUGH = section(Rough, "terrain[] (rough)", "a patch of smooth random bumps", [
    _NAME, _X, _Y, _LENGTH, _WIDTH,
    Number("amplitude", "m", "the bumps' largest height", gt=0, example="amplitude: 0.05"),
    Number("wavelength", "m", "the bumps' typical spacing", gt=0, example="wavelength: 0.5"),
    _SEED, _YAW, _Z])
HEIGHTFIELD = section(Heightfield, "terrain[] (heightfield)", "a height grid read from a greyscale PNG or a "
                      ".npy file beside the scenario", [
    _NAME, _X, _Y,
    Text("file", "", "a .png or .npy file, relative to the scenario's folder and inside it", path=True,
         example="file: ground/yard.png"),
    _LENGTH, _WIDTH,
    Number("min_height", "m", "the height of the grid's lowest value above z"),
    Number("max_height", "m", "the height of the grid's highest value above z"),
    _YAW, _Z], rules=[Rule("max_height is greater than min_height", _heights),
                      Rule("the height file exists, is readable and within the size limits", None)])

TERRAIN = Elements("terrain", "", "ground that is not the flat floor: ramps, steps, platforms, pits, rough "
                   "patches, height grids", max=int(_LIMITS["max_obstacles"]), what="terrain elements",
                   item="terrain element", default=(),
                   example="{type: ramp, x: 3.0, y: 0.0, length: 2.0, width: 1.5, rise: 0.3}", types=tuple(Element(name, decl, name, decl.doc) for name, decl in (
                       ("ramp", RAMP), ("steps", STEPS), ("platform", PLATFORM), ("pit", PIT),
                       ("rough", ROUGH), ("heightfield", HEIGHTFIELD))))

def _mjcf_limits(values: Any, given: Any) -> tuple[str, str, str] | None:
    step, slope = values["max_step"] is not None, values["max_slope"] is not None
    if step != slope or (values["max_gap"] is not None and not step):
        missing = "max_slope" if step else "max_step"
        return (missing, f"an mjcf body's limits are partly declared: declare max_step and max_slope together "
                f"(max_gap may be left out: no gap); {missing} is missing",
                f"add {missing}, or leave all three out (then the path search ignores the terrain for it)")
    return None


def _mjcf_limits_schema(sec: Any, required: list[str]) -> dict[str, Any]:
    """A number (not null: undeclared) for one of them needs numbers for the others."""
    def given(key: str) -> dict[str, Any]:
        return {"required": [key], "properties": {key: {"type": "number"}}}
    return {"allOf": [{"if": given("max_step"), "then": given("max_slope")},
                      {"if": given("max_slope"), "then": given("max_step")},
                      {"if": given("max_gap"), "then": given("max_step")}]}


_TIP = Number("tip_angle", "deg", "roll or pitch that counts as tipped over", gt=0, le=90.0)
WHEELED_BODY = section(WheeledBody, "robot.body (wheeled)", "a wheeled robot riding the terrain on real wheel "
                       "contacts", [
    Choice("drive_wheels", "", "diff: two driven wheels on one axle and casters; skid: four driven wheels",
           options=("diff", "skid")),
    Number("wheel_radius", "m", "the wheels' radius", gt=0),
    Number("wheel_width", "m", "the wheels' width", gt=0),
    Number("track", "m", "lateral wheel spacing (none: the footprint's width)", gt=0, nullable=True),
    Number("wheelbase", "m", "axle spacing, skid only (none: 0.6 × the footprint's length)", gt=0, nullable=True),
    Number("mass", "kg", "chassis and wheels", gt=0),
    Number("max_wheel_torque", "N m", "torque limit per driven wheel", gt=0),
    Number("max_wheel_speed", "rad/s", "wheel speed limit (none: limits.max_speed / wheel_radius)", gt=0,
           nullable=True),
    Number("clearance", "m", "the chassis underside above a flat floor", ge=0),
    _TIP,
    Number("com_height", "m", "the mass centre above the ground (none: the wheels' axle, batteries and "
           "drives low between the wheels)", gt=0, nullable=True)])
LEGGED_BODY = section(LeggedBody, "robot.body (legged)", "a walking robot declared by what it can cross", [
    Number("max_step", "m", "the highest step it climbs", ge=0),
    Number("max_slope", "deg", "the steepest slope it walks", ge=0, le=90.0),
    Number("max_gap", "m", "the widest gap it crosses", ge=0),
    Number("clearance", "m", "its body's underside above the ground", ge=0),
    _TIP])
MJCF_BODY = section(MjcfBody, "robot.body (mjcf)", "the user's own MJCF robot and controller", [
    Text("file", "", "the MJCF file, relative to the scenario's folder and inside it", path=True,
         example="file: robot/robot.xml"),
    Text("controller", "", "pkg.mod:Attr of the controller turning velocity commands into actuator controls",
         example="controller: mypkg.control:Controller"),
    Text("base", "", "the robot's base body (none: the first body with a free joint)", default=None),
    _TIP,
    Number("max_step", "m", "the highest step it climbs, for the path search and the feasibility check "
           "(none: undeclared, the terrain is ignored there)", ge=0, nullable=True),
    Number("max_slope", "deg", "the steepest slope it drives (declared with max_step)", ge=0, le=90.0,
           nullable=True),
    Number("max_gap", "m", "the widest gap it crosses (none: no gap; declared with max_step)", ge=0,
           nullable=True)],
    rules=[Rule("max_step and max_slope are declared together; max_gap only with them", _mjcf_limits,
                _mjcf_limits_schema)])
PLANAR_BODY = section(PlanarBody, "robot.body (planar)", "today's body: planar joints, gravity off", [])

BODY = Variant("body", "", "how the robot meets the ground: planar (the default), wheeled, legged or mjcf",
               types=tuple(Element(name, decl, name, decl.doc) for name, decl in (
                   ("planar", PLANAR_BODY), ("wheeled", WHEELED_BODY), ("legged", LEGGED_BODY),
                   ("mjcf", MJCF_BODY))))


def _lidar3d_ranges(values: Any, given: Any) -> tuple[str, str, str] | None:
    if values["range_max"] <= values["range_min"]:
        return ("range_max", f"range_max ({values['range_max']!r} m) must be greater than range_min "
                f"({values['range_min']!r} m)", "raise range_max")
    if values["fov_high"] < values["fov_low"]:
        return ("fov_high", f"fov_high ({values['fov_high']!r} deg) must not be below fov_low "
                f"({values['fov_low']!r} deg)", "swap them")
    return None


LIDAR3D = section(Lidar3D, "robot.lidar3d", "a spinning multi-ring lidar whose points are part of the "
                  "observation", [
    Integer("rings", "", "rings, spread evenly from fov_low to fov_high", ge=1, le=256),
    Integer("beams", "", "beams per ring over 360 degrees", ge=1, le=int(_LIMITS["max_lidar_beams"])),
    Number("fov_low", "deg", "the lowest ring's elevation", ge=-90.0, le=90.0),
    Number("fov_high", "deg", "the highest ring's elevation", ge=-90.0, le=90.0),
    Number("range_min", "m", "shortest range it reads", ge=0),
    Number("range_max", "m", "longest range", gt=0),
    Number("mount_x", "m", "mounting position on the base, forward"),
    Number("mount_y", "m", "mounting position on the base, left"),
    Number("mount_z", "m", "mounting height above the base's origin"),
    Number("mount_pitch", "deg", "mounting tilt, positive looks down", ge=-90.0, le=90.0),
    Number("noise_sigma", "m", "Gaussian noise on each range", ge=0),
    Number("dropout", "", "probability that a beam reads as no return", ge=0, le=1.0),
    Number("noise_per_metre", "m/m", "the noise's sigma grows by this per metre of range", ge=0, le=1.0),
    Number("dropout_at_max", "", "dropout probability at range_max (none: dropout at every range)", ge=0,
           le=1.0, nullable=True),
    Number("spurious", "", "probability of a spurious return short of the true one", ge=0, le=1.0),
], what="the 3D lidar settings (a mapping)", rules=[
    Rule("range_max is greater than range_min, fov_high not below fov_low", _lidar3d_ranges),
    Rule(f"rings x beams at most {int(_LIMITS['max_lidar3d_rays'])} rays a scan, and its ranges recorded over "
         f"the episode (scans x rings x beams x 4 bytes) at most {int(_LIMITS['max_lidar3d_record_bytes']) >> 30} "
         f"GiB", None)])
