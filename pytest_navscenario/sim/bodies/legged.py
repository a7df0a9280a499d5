"""The legged body: a capability model of a walking robot (an ANYmal), not a walking controller.

What it simulates. The robot is declared by what it can do (``LeggedBody``: ``max_step``,
``max_slope``, ``max_gap``, ``clearance``) and its base follows the ground it can cross:

* each control tick the planner's velocity command (after the drive's limits) gives the way the
  base moves during the tick; the ground along that way is walked (``scenario/ground/crossing.py``) from
  each foot (one at each corner of the footprint) and from the centre;
* a rise higher than ``max_step`` (a step, or a slope steeper than ``max_slope`` rising more than
  that) stops it, its feet at the face: the robot stands there while commanded on, which the
  episode calls *stuck on terrain* after a few seconds; so does steep ground (``crossing.
  steep_ground``: steeper than ``max_slope`` in any direction, over more than ``max_step`` of
  height) that it would walk onto across or diagonally, its feet at the edge (the path search's
  wall there);
* a drop deeper than ``max_step`` with ground back within ``max_gap`` (a trench, a gap between two
  platforms) is strode over; a deeper or wider one is walked into: when the centre passes its edge
  the support goes and the base *falls* under gravity (MuJoCo's physics from then on);
* where it stands, the base rests on the plane through its footholds (feet over a gap it strides
  over are in the air): its height, roll and pitch follow steps, ramps and rough ground, and a
  side slope past ``tip_angle`` counts as tipped over;
* its volume (the footprint, from the ground up to 0.5 m) meets obstacles and moving obstacles:
  a contact is a collision, as for every body.

What it does not simulate: legs, feet, a gait, foot slip, contact forces on the feet, balance,
energy or speed lost on slopes and stairs (it moves at the commanded speed wherever it can go),
stepping over low obstacles (an obstacle is an obstacle, whatever its height), choosing where to
put a foot. It never collides with a terrain face (a face it cannot climb stops it first). A body
that turns in place is not checked (turning is always possible). What it crosses is decided to
2 cm along its way (``crossing.SPACING``).

In MuJoCo: a free base with the footprint's volume (meeting obstacles only) and a torso box from
``clearance`` up (meeting the terrain, so a falling body lands); while supported, gravity is
compensated (``xfrc_applied``) and each tick the base's velocity is set so that it reaches the
tick's end pose exactly (its inertia is a sphere's about its origin: no gyroscopic drift).
"""
from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from ...scenario.ground import surface as ground
from ...scenario.ground.crossing import SPACING, Capability, look_ahead, steep_ground, walk
from ..ground.terrain import GEAR_BITS
from ..world import steps_per_tick
from .base import ROBOT_GROUP, FreeBase, quat_to_rpy, rpy_to_quat

ROBOT_HEIGHT = 0.5        # m: the body's top (as the planar body's), at least clearance + 0.1
LEGGED_MASS = 50.0        # kg (an ANYmal); it matters only once the body falls or is pushed
GRAVITY = 9.81


class LeggedModel(FreeBase):
    """A ``LeggedBody`` in MuJoCo (see the module docstring)."""

    def __init__(self, scenario):
        super().__init__(scenario)
        b = self.spec_body
        self.cap = Capability(float(b.max_step), float(b.max_slope), float(b.max_gap))
        self.clearance = float(b.clearance)
        self.drop_limit = float(b.max_step)     # it walks down what it climbs; deeper is a fall
        fp = scenario.robot.footprint
        if fp.shape == "box":
            self.half = (fp.length / 2, fp.width / 2)
        else:
            self.half = (fp.radius / math.sqrt(2.0), fp.radius / math.sqrt(2.0))
        hl, hw = self.half
        self.feet = np.array([(hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw)])   # feet at the corners
        self.tick_dt = steps_per_tick(scenario) * scenario.simulation.timestep

    def build(self, spec: mujoco.MjSpec) -> None:
        fp = self.scenario.robot.footprint
        top = max(ROBOT_HEIGHT, self.clearance + 0.1)
        robot = spec.worldbody.add_body(name="robot", pos=[0.0, 0.0, 0.0])
        robot.add_freejoint(name="base")
        robot.explicitinertial = True
        robot.mass = LEGGED_MASS
        robot.ipos = [0.0, 0.0, 0.0]
        size = max(self.half) * 2
        robot.inertia = [LEGGED_MASS * size * size / 6.0] * 3      # a sphere's: no gyroscopic terms
        volume = dict(contype=0, conaffinity=2, group=ROBOT_GROUP, rgba=[0.2, 0.4, 0.9, 0.15])
        torso = dict(contype=GEAR_BITS[0], conaffinity=GEAR_BITS[1], group=ROBOT_GROUP, rgba=[0.2, 0.4, 0.9, 1])
        if fp.shape == "circle":
            robot.add_geom(name="footprint", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[fp.radius, top / 2, 0],
                           pos=[0, 0, top / 2], **volume)
            robot.add_geom(name="torso", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                           size=[fp.radius, (top - self.clearance) / 2, 0],
                           pos=[0, 0, (top + self.clearance) / 2], **torso)
        else:
            robot.add_geom(name="footprint", type=mujoco.mjtGeom.mjGEOM_BOX,
                           size=[fp.length / 2, fp.width / 2, top / 2], pos=[0, 0, top / 2], **volume)
            robot.add_geom(name="torso", type=mujoco.mjtGeom.mjGEOM_BOX,
                           size=[fp.length / 2, fp.width / 2, (top - self.clearance) / 2],
                           pos=[0, 0, (top + self.clearance) / 2], **torso)
        robot.add_site(name="centre", pos=[0.0, 0.0, 0.0])

    def bind(self, model: mujoco.MjModel) -> None:
        super().bind(model)
        # the volume meeting obstacles is what collides (the torso meets the terrain only)
        self.chassis_geoms = frozenset([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "footprint")])
        self.robot_geoms = self.chassis_geoms
        self.weight = float(model.body_mass[self.base_body]) * GRAVITY

    def start_height(self, ground_z: float) -> float:
        return ground_z

    def begin(self, d: mujoco.MjData) -> "LeggedGait":
        return LeggedGait(self, d)

    def command(self, ctrl, setpoint, state=None) -> None:   # pragma: no cover - the gait commands
        raise RuntimeError("a legged body is commanded through its gait (begin)")


class LeggedGait:
    """One episode of a legged body: where its feet stand, whether it is supported, and each tick
    the base velocity that takes it to the end of the tick's move (see the module docstring)."""

    def __init__(self, body: LeggedModel, d: mujoco.MjData):
        self.body, self.cap, self.scenario = body, body.cap, body.scenario
        self.qpos, self.qvel = body.views(d)
        self.force = d.xfrc_applied[body.base_body]
        self.force[2] = body.weight                 # supported: gravity compensated
        self.falling = False
        x, y, z = self.qpos[:3].tolist()
        _, _, yaw = _rpy(self.qpos[3:7])
        fx, fy = self._feet(x, y, yaw)
        g = ground.ground_height(self.scenario, fx, fy)
        self.holds = np.where(g >= z - self.cap.max_step, g, z)   # each foot's height

    def _feet(self, x: float, y: float, yaw: float) -> tuple[np.ndarray, np.ndarray]:
        c, s = math.cos(yaw), math.sin(yaw)
        f = self.body.feet
        return x + c * f[:, 0] - s * f[:, 1], y + s * f[:, 0] + c * f[:, 1]

    def command(self, ctrl: np.ndarray, setpoint: tuple[float, float, float], state: Any) -> None:
        """Set the base's velocity for this tick from the setpoint (vx, vy, wz), robot frame."""
        if self.falling:
            return
        cap, dt = self.cap, self.body.tick_dt
        x, y, z, _, _, yaw = state[:6]
        vx, vy, wz = setpoint
        mid = yaw + 0.5 * wz * dt
        c, s = math.cos(mid), math.sin(mid)
        dx, dy = dt * (vx * c - vy * s), dt * (vx * s + vy * c)
        move = math.hypot(dx, dy)
        yaw1 = yaw + wz * dt
        allowed, centre = 0.0, None
        if move > 1e-9:
            ex, ey = dx / move, dy / move
            allowed, centre, falls = self._advance(x, y, z, yaw, ex, ey, move)
            if falls:
                self._fall(dx / dt, dy / dt)
                return
            x1, y1 = x + allowed * ex, y + allowed * ey
        else:
            x1, y1 = x, y
        if centre is None:
            g = float(ground.ground_height(self.scenario, x1, y1))
            centre = g if g >= z - cap.max_step else z
        fx, fy = self._feet(x1, y1, yaw1)
        g = ground.ground_height(self.scenario, fx, fy)
        stands = g >= self.holds - cap.max_step - 1e-9
        z1, gx, gy = _plane(np.append(fx[stands], x1), np.append(fy[stands], y1),
                            np.append(g[stands], centre), x1, y1)
        self.holds = np.where(stands, g, z1 + gx * (fx - x1) + gy * (fy - y1))
        cy, sy = math.cos(yaw1), math.sin(yaw1)
        pitch1 = -math.atan(gx * cy + gy * sy)
        roll1 = math.atan(-gx * sy + gy * cy)
        q1 = np.array(rpy_to_quat(roll1, pitch1, yaw1))
        w = np.zeros(3)
        mujoco.mju_subQuat(w, q1, np.ascontiguousarray(self.qpos[3:7]))
        self.qvel[:3] = ((x1 - x) / dt, (y1 - y) / dt, (z1 - z) / dt)
        self.qvel[3:6] = w / dt

    def _advance(self, x, y, z, yaw, ex, ey, move) -> tuple[float, float | None, bool]:
        """(how far it may go along (ex, ey), the centre's support there, whether the centre goes
        over a drop it cannot cross): the profiles from the centre and each foot."""
        cap = self.cap
        n = look_ahead(cap, move)
        dist = np.arange(n) * SPACING
        fx, fy = self._feet(x, y, yaw)
        sx = np.concatenate([[x], fx])
        sy = np.concatenate([[y], fy])
        px, py = sx[:, None] + ex * dist, sy[:, None] + ey * dist
        h = ground.ground_height(self.scenario, px, py).tolist()
        steep = steep_ground(self.scenario, cap, px, py)
        levels = [z] + self.holds.tolist()
        allowed, centre_walk = move, None
        for i, (profile, level) in enumerate(zip(h, levels)):
            support, barrier = walk(profile, SPACING, level, cap, steep[i] if steep[i].any() else None)
            if i == 0:
                centre_walk = (support, barrier)
            if barrier is not None and barrier.kind != "drop":
                allowed = min(allowed, barrier.index * SPACING)
        support, barrier = centre_walk
        if barrier is not None and barrier.kind == "drop" and allowed > barrier.index * SPACING:
            return allowed, None, True
        k = min(int(allowed / SPACING), n - 2)
        a, b = support[k], support[k + 1]
        frac = allowed / SPACING - k
        centre = a if (frac <= 0.0 or math.isnan(b)) else a + (b - a) * frac
        return allowed, centre, False

    def _fall(self, vx: float, vy: float) -> None:
        """The support goes: gravity acts, the base keeps its horizontal velocity."""
        self.falling = True
        self.force[:] = 0.0
        self.qvel[:] = (vx, vy, 0.0, 0.0, 0.0, 0.0)


def _plane(px: np.ndarray, py: np.ndarray, pz: np.ndarray, x0: float, y0: float) -> tuple[float, float, float]:
    """(height at (x0, y0), slope along x, slope along y) of the least-squares plane through the
    points; level through the last point (the centre) when there are fewer than three."""
    if len(px) < 3:
        return float(pz[-1]), 0.0, 0.0
    a = np.column_stack([np.ones(len(px)), px - x0, py - y0])
    (z0, gx, gy), *_ = np.linalg.lstsq(a, pz, rcond=None)
    return float(z0), float(gx), float(gy)


def _rpy(q: np.ndarray) -> tuple[float, float, float]:
    r, p, y = quat_to_rpy(*q.tolist())
    return float(r), float(p), float(y)
