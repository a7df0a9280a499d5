"""The wheeled body: wheels on the ground under gravity (sim/bodies/wheeled.py builds it), with
the single home of what it can cross: the grip-limited slope (``climbs``) that the safety layer
stops at and the estimates (``capability``) that the path search and the feasibility check use.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal

from ..keys import Choice, Number, section
from .chassis import G, wheeled_layout, wheeled_problem
from .record import TIP, BodyKind, Capability


@dataclass(frozen=True)
class WheeledBody:
    """A wheeled robot riding the terrain under gravity on real wheel contacts: ``diff`` has two
    driven wheels on one axle and passive casters, ``skid`` four driven wheels (skid-steer). A
    low-level controller in the harness turns the planner's velocity command into wheel torques
    within ``max_wheel_torque`` (N m per wheel) and ``max_wheel_speed`` (rad/s; None: the speed
    that gives limits.max_speed). ``track`` (lateral wheel spacing) and ``wheelbase`` (skid: axle
    spacing) default to the footprint's size (the wheels inside it); the mass centre sits
    ``com_height`` above the ground (None: at the wheels' axle). The robot counts as tipped over when
    its roll or pitch passes ``tip_angle`` degrees (scenario/bodies/chassis.py: the layout)."""
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
    TIP,
    Number("com_height", "m", "the mass centre above the ground (none: the wheels' axle, batteries and "
           "drives low between the wheels)", gt=0, nullable=True)])


def climbs(body: WheeledBody) -> float:
    """The steepest slope (degrees) whose weight its driven wheels' torque balances:
    sin(slope) = driven wheels x max_wheel_torque / (mass g wheel_radius), at most 90."""
    driven = 4 if body.drive_wheels == "skid" else 2
    grip = driven * body.max_wheel_torque / (body.mass * G * body.wheel_radius)
    return math.degrees(math.asin(min(grip, 1.0)))


# The wheeled body's limits are estimates from its wheels, measured in MuJoCo with a straight
# drive (benchmarks/measure_wheeled_limits.py; default body: 50 kg, 10 N m, wheels of 0.1 m). The
# figures move between MuJoCo patch releases (the highest step the default diff body climbs at 1 m/s:
# 0.036 m under 4.0.0, 0.042 m under 4.0.1; skid 0.064 -> 0.081 m; the widest gap 0.18 -> 0.23 m), and
# with speed (momentum carries a wheel over a step or a gap it cannot climb slowly: 0.014 m steps and
# 0.11 m gaps at 0.1 m/s, docs/reference/terrain.md), so the estimates are upper bounds with room
# rather than fits: a step is at most the radius of what meets it first (diff: its ball casters,
# 0.05 m; skid: its wheels), since a ball or a wheel cannot roll up a step of its own radius (the
# edge pushes straight back), and at most the chassis' clearance; a slope is at most the one whose
# weight the driven wheels' torque balances, with 10 % room (24.4 deg measured for the default diff
# body at 1 m/s, 20 deg at 0.1 m/s; the casters' springs leave the wheels their grip at a ramp's
# foot), and at most 35 deg (skid: 34-35 at every speed); gaps of 2.4 wheel radii. The estimates
# stay at or above what the body does at every speed under every supported release (pyproject.toml
# pins the series): the shortest path (the metrics' yardstick) and the feasibility check must never
# rule out what the body really crosses (a path round a sill the robot drives over would make its
# path efficiency exceed 1), so a step, slope or gap a little above what it does may pass for
# crossable (tests/verdict/test_traversable.py checks both sides).
WHEELED_CASTER_STEP = 1.0     # of the caster's radius (diff)
WHEELED_WHEEL_STEP = 1.0      # of the wheel's radius (skid)
WHEELED_SLOPE = {"diff": 35.0, "skid": 35.0}   # degrees, at most the torque's limit
WHEELED_TORQUE_SLOPE = 1.1    # the torque's limit (the slope whose weight it balances), over-estimated by this
WHEELED_GAP = 2.4             # of the wheel's radius (0.24 m: the default body crossed 0.18 m under MuJoCo
                              # 4.0.0, 0.23 m under 4.0.1; 0.15 m wheels crossed a rough 0.45 m, not covered)


def capability(body: WheeledBody, footprint: Any) -> Capability:
    """Its estimated limits (see WHEELED_*): a step by its casters (diff) or wheels (skid), the
    slope its torque and grip allow, a gap by its wheels."""
    r = float(body.wheel_radius)
    if body.drive_wheels == "skid":
        step = WHEELED_WHEEL_STEP * r
    else:
        step = WHEELED_CASTER_STEP * wheeled_layout(body, footprint).caster_radius
    return Capability(min(step, float(body.clearance)),
                      min(WHEELED_TORQUE_SLOPE * climbs(body), WHEELED_SLOPE[body.drive_wheels]),
                      WHEELED_GAP * r)


KIND = BodyKind("wheeled", WheeledBody, WHEELED_BODY, drives=("diff",), capability=capability,
                climbs=climbs, problem=wheeled_problem)
