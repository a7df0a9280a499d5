"""The robot of a scenario: frozen dataclasses for its footprint, velocity limits, planar lidar,
safety layer, localisation error and delays, gathered in ``Robot`` with its body (``bodies/``) and
3D lidar (``terrain/``), each followed by the declaration of its YAML keys (``keys.py``), in YAML
units (metres, degrees, seconds). Part of the model (``model.py`` re-exports every name); no I/O.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal, Mapping

from .bodies import BODY, Body, PlanarBody
from .keys import SCENARIO_LIMITS, Choice, Flag, Integer, Number, Rule, Sub, section
from .terrain import LIDAR3D, Lidar3D

DRIVES = ("omni", "diff")
SHAPES = ("box", "circle")


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
