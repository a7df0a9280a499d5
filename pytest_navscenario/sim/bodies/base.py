"""What every body that rides the terrain shares: a base on a free joint (x, y, z and a
quaternion), placed level on the ground at the start pose, read back as x, y, z, roll, pitch, yaw
and velocities; the per-tick work of a body is ``command`` (the setpoint into actuator controls)
and ``state`` (the base's pose and velocity), kept small so that episodes can later be stepped in
lockstep (issue 27).

Frames: the base's origin lies on the ground under the robot's centre when it stands on a flat
floor (so ``z`` is the height of the ground it stands on, and a lidar's ``mount_height`` is above
the ground as for the planar body); its +x is the heading.
"""
from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from ...scenario.model import Scenario

ROBOT_GROUP = 5           # geom group of the robot's own geoms: the lidars skip it


def quat_to_rpy(qw, qx, qy, qz):
    """(roll, pitch, yaw) in radians (Z-Y-X, intrinsic) of unit quaternions (floats or arrays)."""
    roll = np.arctan2(2.0 * (qw * qx + qy * qz), 1.0 - 2.0 * (qx * qx + qy * qy))
    pitch = np.arcsin(np.clip(2.0 * (qw * qy - qz * qx), -1.0, 1.0))
    yaw = np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    return roll, pitch, yaw


def rpy_to_quat(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """The unit quaternion (w, x, y, z) of roll, pitch, yaw (radians; Z-Y-X, intrinsic)."""
    cr, sr = math.cos(roll / 2.0), math.sin(roll / 2.0)
    cp, sp = math.cos(pitch / 2.0), math.sin(pitch / 2.0)
    cy, sy = math.cos(yaw / 2.0), math.sin(yaw / 2.0)
    return (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy)


def world_yaw_rate(quat: np.ndarray, w_local: np.ndarray) -> np.ndarray:
    """The world-frame z component of a body-frame angular velocity (rows of quaternions and
    angular velocities): the turn rate about the vertical."""
    qw, qx, qy, qz = quat[..., 0], quat[..., 1], quat[..., 2], quat[..., 3]
    # third row of the rotation matrix of (qw, qx, qy, qz)
    r20 = 2.0 * (qx * qz - qw * qy)
    r21 = 2.0 * (qy * qz + qw * qx)
    r22 = 1.0 - 2.0 * (qx * qx + qy * qy)
    return r20 * w_local[..., 0] + r21 * w_local[..., 1] + r22 * w_local[..., 2]


class FreeBase:
    """A body whose base is a free joint. Subclasses build the robot into the spec (``build``),
    then ``bind`` the compiled model; ``command`` writes the actuator controls of a setpoint."""

    #: the largest drop (m) the body lands from unharmed; more is a fall
    drop_limit: float = 0.1
    #: roll or pitch (degrees) past which it counts as tipped over
    tip_angle: float = 45.0
    #: the base's origin above the ground it stands on (0: on it; the MJCF body's base is higher)
    ground_offset: float = 0.0

    def __init__(self, scenario: Scenario):
        self.scenario = scenario
        self.spec_body = scenario.robot.body
        self.kind_name = self.spec_body.kind
        self.tip_angle = float(getattr(self.spec_body, "tip_angle", 45.0))

    # -- the model -------------------------------------------------------------------------
    def build(self, spec: mujoco.MjSpec) -> None:
        raise NotImplementedError

    def bind(self, model: mujoco.MjModel) -> None:
        """Ids of the compiled model: the base body, its free joint's qpos/qvel addresses."""
        self.base_body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "robot")
        joint = model.body_jntadr[self.base_body]
        self.qadr = int(model.jnt_qposadr[joint])
        self.vadr = int(model.jnt_dofadr[joint])
        self.chassis_geoms = frozenset(
            g for g in range(model.ngeom)
            if model.geom_bodyid[g] == self.base_body and model.geom_contype[g] & 1)
        self.robot_geoms = self.chassis_geoms       # the geoms that meet obstacles

    # -- per episode -----------------------------------------------------------------------
    def place(self, d: mujoco.MjData, x: float, y: float, yaw: float, z: float,
              roll: float = 0.0, pitch: float = 0.0) -> None:
        """Put the base at (x, y, z) heading ``yaw``, tilted by ``roll`` and ``pitch`` (at rest)."""
        q = d.qpos
        a = self.qadr
        q[a:a + 3] = (x, y, z)
        q[a + 3:a + 7] = rpy_to_quat(roll, pitch, yaw)

    def start_height(self, ground_z: float) -> float:
        """The base's z at the start: on the ground (a hair above, so it settles onto it)."""
        return ground_z + 0.002

    def begin(self, d: mujoco.MjData) -> Any:
        """The body's controller for one episode on ``d``, called once the base is placed: an
        object with ``command``. A body that keeps nothing per episode (wheeled) is its own."""
        return self

    # -- per tick (small: batched later) ---------------------------------------------------
    def command(self, ctrl: np.ndarray, setpoint: tuple[float, float, float], state: Any) -> None:
        raise NotImplementedError

    def views(self, d: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """(qpos row of the base (7,), qvel row (6,)): live views, recorded each physics step."""
        return d.qpos[self.qadr:self.qadr + 7], d.qvel[self.vadr:self.vadr + 6]


def base_state(qpos7: np.ndarray, qvel6: np.ndarray) -> tuple[float, ...]:
    """(x, y, z, roll, pitch, yaw, vx, vy, vz, wz) of a base: velocities in the heading frame
    (vx forward, vy left, both horizontal), wz the turn rate about the vertical."""
    x, y, z, qw, qx, qy, qz = qpos7.tolist()
    wvx, wvy, wvz, wx, wy, wzl = qvel6.tolist()
    roll = math.atan2(2.0 * (qw * qx + qy * qz), 1.0 - 2.0 * (qx * qx + qy * qy))
    sp = 2.0 * (qw * qy - qz * qx)
    pitch = math.asin(1.0 if sp > 1.0 else (-1.0 if sp < -1.0 else sp))
    yaw = math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    wz = (2.0 * (qx * qz - qw * qy) * wx + 2.0 * (qy * qz + qw * qx) * wy
          + (1.0 - 2.0 * (qx * qx + qy * qy)) * wzl)
    c, s = math.cos(yaw), math.sin(yaw)
    return x, y, z, roll, pitch, yaw, c * wvx + s * wvy, -s * wvx + c * wvy, wvz, wz
