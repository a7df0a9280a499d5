"""Where a wheeled body's parts sit and whether it can stand: the one layout that the MuJoCo model
(sim/bodies/wheeled.py), the loader's checks and the crossing estimates (scenario/ground/crossing.py) share.

Robot frame: x forward, y left, z up from the ground under the footprint's centre.

* ``diff``: two driven wheels on one axle through the centre, ``track`` apart; two sprung ball
  casters on the centre line at the front and the back of the footprint;
* ``skid``: four driven wheels, ``wheelbase`` apart front to back, ``track`` apart side to side;
* the mass centre at ``com_height`` (default: the wheels' axle; batteries and drives sit low
  between the wheels, as on most delivery and warehouse robots).

A body stands on flat ground at its limits when it can neither tip over its front or back support
(the casters' contacts, or the skid's axles) accelerating or braking at the acceleration it can
reach, nor over its wheels turning at its top speed and yaw rate: ``stability_problem`` says which
limit to change when it cannot. Such a robot would pop a wheelie or roll over in the simulation as
it would on the floor: the loader refuses it rather than run it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

G = 9.81
FRICTION = 1.0            # the wheels' sliding friction (sim/ground/terrain.py: rubber on concrete)
TIP_MARGIN = 0.8          # the share of the tipping acceleration a body may reach (dynamic overshoot)
MIN_CASTER = 0.02         # m: the smallest ball caster
FIT = 1e-6                # m: rounding allowed when checking that the wheels fit the footprint


@dataclass(frozen=True)
class WheeledLayout:
    """A wheeled body's geometry (metres, robot frame)."""
    length: float               # the footprint's extent along x
    width: float                # and along y
    radius: float               # the wheels'
    wheel_width: float
    track: float                # left to right wheel centres
    wheelbase: float            # front to back axles (skid; 0 for diff)
    skid: bool
    caster_radius: float        # diff's ball casters (0 for skid)
    caster_x: float             # their centres' distance ahead of and behind the axle (0 for skid)
    com_height: float           # the mass centre above the ground

    @property
    def wheels(self) -> tuple[tuple[float, float], ...]:
        """(x, y) of each driven wheel's centre, left ones first."""
        h = self.track / 2
        if self.skid:
            w = self.wheelbase / 2
            return ((w, h), (-w, h), (w, -h), (-w, -h))
        return ((0.0, h), (0.0, -h))

    @property
    def support(self) -> float:
        """How far ahead of (and behind) the centre the body stands on the ground: the line it
        tips over accelerating or braking (the casters' contacts, or the skid's axles)."""
        return self.wheelbase / 2 if self.skid else self.caster_x


def wheeled_layout(body, footprint) -> WheeledLayout:
    """The layout of a ``WheeledBody`` on a footprint: ``track`` (default: the wheels just inside
    the footprint's sides; in a circle, their outer corners on it), ``wheelbase`` (skid; default
    0.6 of the length, shortened until the wheels fit; in a circle, the corners at 45 degrees), the
    casters (radius half the wheels', at most the clearance, at the footprint's ends) and the mass
    centre."""
    r, w = float(body.wheel_radius), float(body.wheel_width)
    skid = body.drive_wheels == "skid"
    if footprint.shape == "circle":
        radius = float(footprint.radius)
        length = width = 2 * radius
        # the wheels' outer corners on the circle: at 45 degrees (skid), or beside the centre (diff)
        side = radius / math.sqrt(2) if skid else math.sqrt(max(radius * radius - r * r, 0.0))
        track = 2 * side - w
        wheelbase = 2 * (radius / math.sqrt(2) - r) if skid else 0.0
    else:
        length, width = float(footprint.length), float(footprint.width)
        track = width - w
        wheelbase = min(0.6 * length, length - 2 * r) if skid else 0.0
    track = float(body.track) if body.track is not None else track
    if skid and body.wheelbase is not None:
        wheelbase = float(body.wheelbase)
    caster_r = caster_x = 0.0
    if not skid:
        caster_r = max(MIN_CASTER, min(float(body.clearance), r / 2))
        caster_x = length / 2 - caster_r
    com = float(body.com_height) if getattr(body, "com_height", None) is not None else r
    return WheeledLayout(length, width, r, w, track, wheelbase, skid, caster_r, caster_x, com)


def reachable_accel(body, limits, layout: WheeledLayout) -> float:
    """The largest acceleration (m/s²) the body reaches on flat ground: its drive's limit, or
    what its wheels' torque or grip give, whichever is less."""
    driven = len(layout.wheels)
    torque = driven * float(body.max_wheel_torque) / (layout.radius * float(body.mass))
    return min(float(limits.max_accel), torque, FRICTION * G)


def fit_problem(body, footprint, layout: WheeledLayout) -> tuple[str, str, str] | None:
    """(field, message, fix) when the wheels or casters do not fit inside the footprint."""
    r, w = layout.radius, layout.wheel_width
    if layout.track <= 0:
        size = (f"a circle of radius {footprint.radius:g} m" if footprint.shape == "circle"
                else f"a footprint {layout.width:g} m wide")
        return ("robot.body.track" if body.track is not None else "robot.body.wheel_width",
                f"wheels of radius {r:g} m and {w:g} m wide leave no track between them in {size}",
                "give smaller or narrower wheels, or a larger footprint")
    if layout.skid and layout.wheelbase <= 0:
        return ("robot.body.wheel_radius", f"four wheels of radius {r:g} m do not fit one behind the other "
                f"in a footprint {layout.length:g} m long", "give smaller wheels or a longer footprint")
    outer_y = layout.track / 2 + w / 2
    outer_x = (layout.wheelbase / 2 if layout.skid else 0.0) + r
    if footprint.shape == "circle":
        outside = math.hypot(outer_x, outer_y) > footprint.radius + FIT
        size = f"a circle of radius {footprint.radius:g} m"
    else:
        outside = outer_x > layout.length / 2 + FIT or outer_y > layout.width / 2 + FIT
        size = f"a footprint {layout.length:g} x {layout.width:g} m"
    if outside:
        keys = [k for k in ("track", "wheelbase") if getattr(body, k) is not None]
        return (f"robot.body.{keys[0]}" if keys else "robot.body.wheel_radius",
                f"the wheels (radius {r:g} m, {w:g} m wide, their outer edges {outer_x:.3g} m ahead of the "
                f"centre and {outer_y:.3g} m to its side) stick out of {size}",
                "give smaller wheels, a narrower track" + (" or wheelbase" if layout.skid else "")
                + ", or a larger footprint (the footprint is the robot's whole outline)")
    rc = layout.caster_radius
    if not layout.skid and (layout.caster_x <= 0 or (layout.caster_x - rc < r and layout.track / 2 - w / 2 < rc)):
        return ("robot.body.wheel_radius",
                f"a footprint {layout.length:g} m long has no room for ball casters (radius {rc:g} m) ahead of "
                f"and behind wheels of radius {r:g} m",
                f"give smaller wheels, or a footprint at least {2 * (r + 2 * rc):.3g} m long")
    return None


def stability_problem(body, limits, layout: WheeledLayout) -> tuple[str, str, str] | None:
    """(field, message, fix) when the body would tip over on flat ground within its own limits:
    over its front or back support accelerating or braking, or over its wheels turning."""
    h = layout.com_height
    accel = reachable_accel(body, limits, layout)
    tip = G * layout.support / h
    if accel > TIP_MARGIN * tip:
        ok = TIP_MARGIN * tip
        driven = len(layout.wheels)
        by_torque = driven * float(body.max_wheel_torque) / (layout.radius * float(body.mass)) == accel \
            and accel < float(limits.max_accel)      # the torque binds (else max_accel, or the grip)
        lower = (f"lower max_wheel_torque to at most {ok * layout.radius * float(body.mass) / driven:.3g} N m"
                 if by_torque else f"lower robot.limits.max_accel to at most {ok:.3g}")
        return ("robot.body.max_wheel_torque" if by_torque else "robot.limits.max_accel",
                f"the wheeled body would tip over accelerating or braking at {accel:.3g} m/s²: its mass "
                f"{h:.3g} m up and its {'axles' if layout.skid else 'casters'} {layout.support:.3g} m ahead of "
                f"and behind its centre tip it past {tip:.3g} m/s² (accepted: up to {100 * TIP_MARGIN:g} % of "
                f"that, {ok:.3g})",
                f"{lower}, lower com_height, or lengthen the footprint")
    # sideways, the wheels slide past FRICTION * G before anything rolls over
    turn = min(float(limits.max_speed) * math.radians(float(limits.max_yaw_rate)), FRICTION * G)
    roll_tip = G * (layout.track / 2) / h
    if turn > TIP_MARGIN * roll_tip:
        return ("robot.limits.max_yaw_rate",
                f"the wheeled body would roll over turning at its top speed and yaw rate ({turn:.3g} m/s² "
                f"sideways): its mass {h:.3g} m up and its wheels {layout.track:.3g} m apart roll it over past "
                f"{roll_tip:.3g} m/s² (accepted: up to {100 * TIP_MARGIN:g} % of that)",
                "lower max_speed or max_yaw_rate, lower com_height, or widen the track")
    return None


def wheeled_problem(scenario) -> tuple[str, str, str] | None:
    """(field, message, fix) when the scenario's wheeled body cannot be built inside its footprint
    or cannot stand within its limits; None when it can (or the body is not wheeled)."""
    body = scenario.robot.body
    if body.kind != "wheeled":
        return None
    layout = wheeled_layout(body, scenario.robot.footprint)
    return (fit_problem(body, scenario.robot.footprint, layout)
            or stability_problem(body, scenario.robot.limits, layout))
