"""The wheeled body: a chassis on a free joint riding the terrain under gravity on real wheel
contacts, and its low-level controller (the planner's velocity command -> wheel speeds -> torques).

Geometry (robot frame, the base's origin on the ground under the centre; ``scenario/bodies/chassis.py``
places the parts and the loader refuses a body that cannot stand within its limits):

* the chassis: the footprint (a box, or a cylinder for a circle) from ``clearance`` above the
  ground up to ROBOT_HEIGHT (0.5 m, as the planar body) is its collision shape; its mass sits at
  ``com_height`` (default: the wheels' axle: batteries and drives low between the wheels), so the
  chassis balances on its axle instead of standing on it like an inverted pendulum;
* ``diff``: two driven wheels on one axle through the centre, ``track`` apart, and two sprung ball
  casters at the front and the back of the footprint (frictionless spheres on vertical springs with
  a small preload: they steady the chassis's pitch and carry little load, so the driven wheels keep
  their traction); the springs are soft enough that the wheels keep their load where the ground
  bends by up to SUSPENSION_SLOPE (the foot and the top of a ramp), with the travel to follow half
  of such a bend, and stiff enough that the drive's full acceleration pitches the chassis at most
  ACCEL_PITCH standing (a short robot with a high mass centre gets the stiffer springs: issue 36.1,
  stiffer casters took the chassis's weight off its wheels at a ramp's foot);
* ``skid``: four driven wheels, ``wheelbase`` apart front to back, ``track`` apart side to side;
  it turns by skidding (the wheels' sideways friction resists, as on a real skid-steer).

Wheels are cylinders of ``wheel_radius`` and ``wheel_width`` on hinge joints, friction 1 (rubber on
concrete). Each is driven by the low-level controller, a proportional-integral wheel-speed loop
whose torque saturates at ``max_wheel_torque`` (on the joint: ``actuatorfrcrange``): a MuJoCo
velocity actuator (the proportional part: its gain gives the wheel the planar body's tracking time
constant TRACKING_TAU for its share of the robot's inertia) and an integrator actuator pulling the
wheel towards the integral of its target speed (critically damped with it, and held within the
angle error that gives full torque: anti-windup). Real motor controllers hold speed under load;
a proportional loop alone gave a slow target little torque (issue 36.1: the body climbed less
slowly). Each
control tick the planner's setpoint (vx, wz) becomes the wheel speeds (vx -+ wz track / 2) / r,
scaled down together when one would pass ``max_wheel_speed``, and the loop's target ramps to them
over the tick (an integrator in the actuator) rather than jumping: the drive's acceleration limit
holds within the tick as well as from tick to tick, so the wheels do not kick the chassis at full
torque each tick. So a slope slows the robot when the torque saturates, a step taller than a wheel
can climb stops it, and nothing is scripted.
"""
from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from ...scenario.bodies.chassis import G, wheeled_layout
from ..ground.terrain import CHASSIS_BITS, GEAR_BITS
from ..world import steps_per_tick
from .base import ROBOT_GROUP, FreeBase

ROBOT_HEIGHT = 0.5        # m: the chassis's top, as the planar body's
WHEEL_MASS_SHARE = 0.04   # of the body's mass, per wheel
CASTER_MASS_SHARE = 0.01  # of the body's mass, per caster
DECK = 0.1                # m: the thickness of the slab the chassis's mass is spread over (its inertia)
CASTER_PRELOAD = 0.05     # of the body's weight, carried by each caster standing on flat ground
SUSPENSION_SLOPE = 30.0   # degrees: a bend of the ground under the casters that leaves the wheels loaded
ACCEL_PITCH = 2.0         # degrees: the chassis's standing pitch on its casters at the drive's full acceleration
# MuJoCo's contacts are soft in proportion to the mass behind them: a caster's own small mass would
# make its contact softer than its spring (measured: a 0.3 kg caster sank 8 mm into the floor and let
# a 0.3 m robot pitch 10 degrees accelerating at 2 m/s²). The slide's armature (inertia felt by the
# spring's motion, not by gravity) puts a tenth of the robot's mass behind it, so the spring sets the
# pitch (5 degrees there).
CASTER_ARMATURE_SHARE = 0.1
TRACKING_TAU = 0.02       # s: the wheel speed loop's time constant (steady error ~1 % at full torque)


class WheeledModel(FreeBase):
    """A ``WheeledBody`` in MuJoCo (see the module docstring)."""

    def __init__(self, scenario):
        super().__init__(scenario)
        b = self.spec_body
        self.layout = wheeled_layout(b, scenario.robot.footprint)
        self.radius = self.layout.radius
        self.track = self.layout.track
        self.skid = self.layout.skid
        limits = scenario.robot.limits
        self.max_speed = (float(b.max_wheel_speed) if b.max_wheel_speed is not None
                          else limits.max_speed / self.radius * 1.2)   # 20 % headroom over the limit
        self.drop_limit = self.radius
        self.tick_dt = steps_per_tick(scenario) * scenario.simulation.timestep

    def wheel_positions(self) -> list[tuple[float, float]]:
        """(x, y) of each driven wheel's centre in the robot frame, left first."""
        return list(self.layout.wheels)

    def build(self, spec: mujoco.MjSpec) -> None:
        b, fp, lay = self.spec_body, self.scenario.robot.footprint, self.layout
        r, m = self.radius, float(b.mass)
        wheels = lay.wheels
        wheel_mass = WHEEL_MASS_SHARE * m
        casters = 0 if self.skid else 2
        caster_mass = CASTER_MASS_SHARE * m
        chassis_mass = max(m - wheel_mass * len(wheels) - caster_mass * casters, 0.1 * m)
        top = max(ROBOT_HEIGHT, b.clearance + 0.1)
        robot = spec.worldbody.add_body(name="robot", pos=[0.0, 0.0, 0.0])
        robot.add_freejoint(name="base")
        # the chassis's mass: a slab over the footprint centred at com_height (its geoms carry none)
        robot.explicitinertial = True
        robot.mass = chassis_mass
        robot.ipos = [0.0, 0.0, lay.com_height]
        lx, ly = lay.length, lay.width
        robot.inertia = [chassis_mass / 12 * (ly * ly + DECK * DECK), chassis_mass / 12 * (lx * lx + DECK * DECK),
                         chassis_mass / 12 * (lx * lx + ly * ly)]
        chassis = dict(contype=CHASSIS_BITS[0], conaffinity=CHASSIS_BITS[1], group=ROBOT_GROUP,
                       rgba=[0.2, 0.4, 0.9, 1])
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
        inertia = m / len(wheels) * r * r
        kv = inertia / TRACKING_TAU
        for k, (wx, wy) in enumerate(wheels):
            wheel = robot.add_body(name=f"wheel{k}", pos=[wx, wy, r])
            joint = wheel.add_joint(name=f"wheel{k}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0])
            # the loop's sum (proportional + integral) saturates at the motor's torque
            joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_TRUE
            joint.actfrcrange = [-b.max_wheel_torque, b.max_wheel_torque]
            wheel.add_geom(name=f"wheel{k}", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                           size=[r, b.wheel_width / 2, 0], quat=[math.sqrt(0.5), math.sqrt(0.5), 0, 0],
                           mass=wheel_mass, friction=[1.0, 0.005, 0.0001], rgba=[0.1, 0.1, 0.1, 1], **gear)
            act = spec.add_actuator(name=f"wheel{k}", trntype=mujoco.mjtTrn.mjTRN_JOINT, target=f"wheel{k}")
            act.set_to_velocity(kv=kv)
            act.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR    # the target (act) ramps at the rate ctrl
            act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            act.forcerange = [-b.max_wheel_torque, b.max_wheel_torque]
        self.ki = inertia / (4 * TRACKING_TAU * TRACKING_TAU)     # critically damped with kv
        for k in range(len(wheels)):
            # the loop's integral action: its target angle (act) integrates the wheel speed target
            # (ctrl: the tick's mean target), and it pulls the wheel to that angle with ki
            act = spec.add_actuator(name=f"wheel{k}_integral", trntype=mujoco.mjtTrn.mjTRN_JOINT,
                                    target=f"wheel{k}")
            act.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR
            act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
            act.gainprm[0] = self.ki
            act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
            act.biasprm[:3] = [0.0, -self.ki, 0.0]
        if casters:
            self._add_casters(robot, chassis_mass, caster_mass, gear)

    def _add_casters(self, robot, chassis_mass: float, caster_mass: float, gear: dict) -> None:
        """Two ball casters on vertical springs at the front and back (see the module docstring):
        stiffness from SUSPENSION_SLOPE (or ACCEL_PITCH, whichever is stiffer), damping critical for
        the chassis's pitch on them, a preload of CASTER_PRELOAD of the weight each; travel of the
        caster's radius down, and up half of what a SUSPENSION_SLOPE bend asks."""
        lay, m = self.layout, float(self.spec_body.mass)
        rc, d = lay.caster_radius, lay.caster_x
        # soft enough for the ground's bends, stiff enough that the drive's hardest acceleration
        # (its torque's reaction and the mass centre's inertia, m a h about the axle) pitches the
        # chassis at most ACCEL_PITCH standing (short robots with a high mass centre need the latter)
        accel = float(self.scenario.robot.limits.max_accel)
        stiffness = max(m * G / (d * math.tan(math.radians(SUSPENSION_SLOPE))),
                        m * accel * lay.com_height / (2 * d * d * math.radians(ACCEL_PITCH)))
        pitch_inertia = chassis_mass / 12 * (lay.length ** 2 + DECK * DECK) + chassis_mass * (lay.com_height - lay.radius) ** 2
        damping = max(math.sqrt(stiffness * d * d * pitch_inertia) / (d * d),
                      stiffness * self.scenario.simulation.timestep)   # the latter: stable at any step
        for k, cx in enumerate((d, -d)):
            caster = robot.add_body(name=f"caster{k}", pos=[cx, 0.0, rc])
            joint = caster.add_joint(name=f"caster{k}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
            joint.stiffness = [stiffness, 0.0, 0.0]
            joint.damping = [damping, 0.0, 0.0]
            joint.springref = -CASTER_PRELOAD * m * G / stiffness
            joint.armature = CASTER_ARMATURE_SHARE * m
            joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            joint.range = [-rc, d * math.tan(math.radians(SUSPENSION_SLOPE)) / 2]
            # frictionless: a ball caster rolls any way (condim 1, and its priority makes the
            # contact take the caster's settings rather than the ground's)
            caster.add_geom(name=f"caster{k}", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[rc, 0, 0],
                            mass=caster_mass, condim=1, priority=1, rgba=[0.3, 0.3, 0.3, 1], **gear)

    def bind(self, model: mujoco.MjModel) -> None:
        super().bind(model)
        self.n_wheels = len(self.layout.wheels)
        self.half = self.n_wheels // 2          # left wheels first
        self.wheel_qpos = [int(model.jnt_qposadr[model.joint(f"wheel{k}").id]) for k in range(self.n_wheels)]

    def begin(self, d: mujoco.MjData) -> "WheelSpeeds":
        return WheelSpeeds(self, d)

    def wheel_speeds(self, setpoint: tuple[float, float, float]) -> tuple[float, float]:
        """(left, right) wheel speeds (rad/s) for the setpoint (vx, wz) (a wheeled body has no vy)."""
        vx, _, wz = setpoint
        r, half_track = self.radius, self.track / 2
        left = (vx - wz * half_track) / r
        right = (vx + wz * half_track) / r
        peak = max(abs(left), abs(right))
        if peak > self.max_speed:
            left, right = left * self.max_speed / peak, right * self.max_speed / peak
        return left, right

    def command(self, ctrl: np.ndarray, setpoint: tuple[float, float, float], state: Any = None) -> None:
        raise RuntimeError("a wheeled body is commanded through its wheel speed loop (begin)")


class WheelSpeeds:
    """One episode's low-level controller of a wheeled body: each tick, the rates (``ctrl``) that
    ramp the wheel-speed loops' targets (``act``) from where they are to the setpoint's wheel
    speeds over exactly one control tick, the integral actuators' rates (the ramp's mean speed)
    and their target angles held within full torque of the wheels' (anti-windup)."""

    def __init__(self, body: WheeledModel, d: mujoco.MjData):
        self.body, self.act, self.qpos = body, d.act, d.qpos
        self.half, self.n = body.half, body.n_wheels
        self.rate = 1.0 / body.tick_dt
        self.angles = body.wheel_qpos           # the wheels' angles in qpos
        self.wind = float(body.spec_body.max_wheel_torque) / body.ki   # anti-windup: the angle error at full torque

    def command(self, ctrl: np.ndarray, setpoint: tuple[float, float, float], state: Any = None) -> None:
        left, right = self.body.wheel_speeds(setpoint)
        act, rate, n, half = self.act, self.rate, self.n, self.half
        qpos, angles, wind = self.qpos, self.angles, self.wind
        for k in range(n):
            target = left if k < half else right
            ctrl[n + k] = (target + act[k]) / 2        # the ramp's mean: the target angle's rate
            ctrl[k] = (target - act[k]) * rate
            angle = qpos[angles[k]]                   # anti-windup: the integral holds at most full torque
            act[n + k] = min(max(act[n + k], angle - wind), angle + wind)
