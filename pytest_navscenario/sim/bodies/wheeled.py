"""The wheeled body: a chassis on a free joint riding the terrain under gravity on real wheel
contacts, and its low-level controller (the planner's velocity command -> wheel speeds -> torques).

Geometry (robot frame, the base's origin on the ground under the centre):

* the chassis: the footprint (a box, or a cylinder for a circle) from ``clearance`` above the
  ground up to ROBOT_HEIGHT (0.5 m, as the planar body), carrying the mass less the wheels';
* ``diff``: two driven wheels on one axle through the centre, ``track`` apart, and two spring-loaded
  ball casters at the front and back of the footprint (frictionless spheres on a vertical spring:
  they keep the chassis level and carry little load, so the driven wheels keep their traction);
* ``skid``: four driven wheels, ``wheelbase`` apart front to back, ``track`` apart side to side;
  it turns by skidding (the wheels' sideways friction resists, as on a real skid-steer).

Wheels are cylinders of ``wheel_radius`` and ``wheel_width`` on hinge joints, friction 1 (rubber on
concrete). Each is driven by a MuJoCo velocity actuator, the low-level controller: a proportional
wheel-speed loop whose torque saturates at ``max_wheel_torque``; its gain gives the wheel the
planar body's tracking time constant (TRACKING_TAU) for its share of the robot's inertia. Each
control tick the planner's setpoint (vx, wz) becomes the wheel speeds (vx -+ wz track / 2) / r,
scaled down together when one would pass ``max_wheel_speed``. So a slope slows the robot when the
torque saturates, a step taller than a wheel can climb stops it, and nothing is scripted.
"""
from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from ..terrain import CHASSIS_BITS, GEAR_BITS
from .base import ROBOT_GROUP, FreeBase

ROBOT_HEIGHT = 0.5        # m: the chassis's top, as the planar body's
WHEEL_MASS_SHARE = 0.04   # of the body's mass, per wheel
CASTER_MASS = 0.3         # kg
CASTER_STIFFNESS = 8000.0  # N/m (measured: see the docstring)
CASTER_DAMPING = 400.0    # N s/m
TRACKING_TAU = 0.02       # s: the wheel speed loop's time constant (steady error ~1 % at full torque)


class WheeledModel(FreeBase):
    """A ``WheeledBody`` in MuJoCo (see the module docstring)."""

    def __init__(self, scenario):
        super().__init__(scenario)
        b = self.spec_body
        fp = scenario.robot.footprint
        self.length = fp.length if fp.shape == "box" else 2 * fp.radius
        self.width = fp.width if fp.shape == "box" else 2 * fp.radius
        self.radius = float(b.wheel_radius)
        self.track = float(b.track) if b.track is not None else self.width - b.wheel_width
        self.wheelbase = float(b.wheelbase) if b.wheelbase is not None else 0.6 * self.length
        self.skid = b.drive_wheels == "skid"
        limits = scenario.robot.limits
        self.max_speed = (float(b.max_wheel_speed) if b.max_wheel_speed is not None
                          else limits.max_speed / self.radius * 1.2)   # 20 % headroom over the limit
        self.drop_limit = self.radius
        self.caster_radius = max(0.02, min(b.clearance, self.radius / 2))

    def wheel_positions(self) -> list[tuple[float, float]]:
        """(x, y) of each driven wheel's centre in the robot frame, left first."""
        h = self.track / 2
        if self.skid:
            w = self.wheelbase / 2
            return [(w, h), (-w, h), (w, -h), (-w, -h)]
        return [(0.0, h), (0.0, -h)]

    def build(self, spec: mujoco.MjSpec) -> None:
        b, fp = self.spec_body, self.scenario.robot.footprint
        r = self.radius
        wheels = self.wheel_positions()
        wheel_mass = WHEEL_MASS_SHARE * b.mass
        casters = 0 if self.skid else 2
        chassis_mass = max(b.mass - wheel_mass * len(wheels) - CASTER_MASS * casters, 0.1 * b.mass)
        top = max(ROBOT_HEIGHT, b.clearance + 0.1)
        robot = spec.worldbody.add_body(name="robot", pos=[0.0, 0.0, 0.0])
        robot.add_freejoint(name="base")
        chassis = dict(contype=CHASSIS_BITS[0], conaffinity=CHASSIS_BITS[1], group=ROBOT_GROUP,
                       rgba=[0.2, 0.4, 0.9, 1], mass=chassis_mass)
        if fp.shape == "circle":
            robot.add_geom(name="footprint", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                           size=[fp.radius, (top - b.clearance) / 2, 0], pos=[0, 0, (top + b.clearance) / 2],
                           **chassis)
        else:
            robot.add_geom(name="footprint", type=mujoco.mjtGeom.mjGEOM_BOX,
                           size=[fp.length / 2, fp.width / 2, (top - b.clearance) / 2],
                           pos=[0, 0, (top + b.clearance) / 2], **chassis)
        robot.add_site(name="centre", pos=[0.0, 0.0, 0.0])
        gear = dict(contype=GEAR_BITS[0], conaffinity=GEAR_BITS[1], group=ROBOT_GROUP)
        # wheel speed loop: the wheel's share of the robot's inertia, reflected through its radius
        inertia = b.mass / len(wheels) * r * r
        kv = inertia / TRACKING_TAU
        for k, (wx, wy) in enumerate(wheels):
            wheel = robot.add_body(name=f"wheel{k}", pos=[wx, wy, r])
            wheel.add_joint(name=f"wheel{k}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0])
            wheel.add_geom(name=f"wheel{k}", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                           size=[r, b.wheel_width / 2, 0], quat=[math.sqrt(0.5), math.sqrt(0.5), 0, 0],
                           mass=wheel_mass, friction=[1.0, 0.005, 0.0001], rgba=[0.1, 0.1, 0.1, 1], **gear)
            act = spec.add_actuator(name=f"wheel{k}", trntype=mujoco.mjtTrn.mjTRN_JOINT, target=f"wheel{k}")
            act.set_to_velocity(kv=kv)
            act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            act.forcerange = [-b.max_wheel_torque, b.max_wheel_torque]
        rc = self.caster_radius
        for k in range(casters):
            cx = (1 if k == 0 else -1) * (self.length / 2 - rc)
            caster = robot.add_body(name=f"caster{k}", pos=[cx, 0.0, rc])
            joint = caster.add_joint(name=f"caster{k}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
            joint.stiffness = [CASTER_STIFFNESS, 0.0, 0.0]
            joint.damping = [CASTER_DAMPING, 0.0, 0.0]
            joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            joint.range = [-rc, rc]
            # frictionless: a ball caster rolls any way (condim 1, and its priority makes the
            # contact take the caster's settings rather than the ground's)
            caster.add_geom(name=f"caster{k}", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[rc, 0, 0],
                            mass=CASTER_MASS, condim=1, priority=1, rgba=[0.3, 0.3, 0.3, 1], **gear)

    def bind(self, model: mujoco.MjModel) -> None:
        super().bind(model)
        self.n_wheels = len(self.wheel_positions())
        self.half = len(self.wheel_positions()) // 2          # left wheels first

    def command(self, ctrl: np.ndarray, setpoint: tuple[float, float, float], state: Any = None) -> None:
        """Wheel speed targets for the setpoint (vx, wz) (a wheeled body has no vy)."""
        vx, _, wz = setpoint
        r, half_track = self.radius, self.track / 2
        left = (vx - wz * half_track) / r
        right = (vx + wz * half_track) / r
        peak = max(abs(left), abs(right))
        if peak > self.max_speed:
            left, right = left * self.max_speed / peak, right * self.max_speed / peak
        n = self.half
        ctrl[:n] = left
        ctrl[n:2 * n] = right
