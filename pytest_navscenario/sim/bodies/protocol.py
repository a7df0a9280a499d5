"""What the simulation asks of a body that rides the ground (``BodyModel``) and of its per-episode
controller (``BodyControl``): the interface a new kind of body implements (``base.FreeBase`` gives
most of it for a base on a free joint; ``wheeled.py``, ``legged.py`` and ``mjcf.py`` are the three
kinds)."""
from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import mujoco
import numpy as np


@runtime_checkable
class BodyControl(Protocol):
    """A body's controller for one episode: the planner's setpoint into actuator controls."""

    def command(self, ctrl: np.ndarray, setpoint: tuple[float, float, float], state: Any) -> None:
        """Write the actuator controls of ``setpoint`` (vx, vy, wz; the drive's limits applied)
        into ``ctrl``, given the base's ``state`` (riding.base_state's tuple)."""


@runtime_checkable
class BodyModel(Protocol):
    """A kind of body as the simulation builds and runs it (one per scenario, shared by its
    episodes). After ``bind``: ``base_body`` (the base's body id), ``chassis_geoms`` (the geoms
    whose contact with terrain faces or obstacles counts), ``robot_geoms`` (those that meet
    obstacles)."""

    kind_name: str          # the scenario's robot.body kind
    drop_limit: float       # m: the largest drop it lands from unharmed; more is a fall
    tip_angle: float        # degrees of roll or pitch past which it has tipped over
    ground_offset: float    # m: its base's origin above the ground it stands on
    base_body: int
    chassis_geoms: frozenset
    robot_geoms: frozenset

    def build(self, spec: mujoco.MjSpec) -> None:
        """Add the robot (its base on a free joint named after the ``robot`` body) to the spec."""

    def bind(self, model: mujoco.MjModel) -> None:
        """Read the compiled model's ids (``base_body``, ``chassis_geoms``, ``robot_geoms``)."""

    def place(self, d: mujoco.MjData, x: float, y: float, yaw: float, z: float,
              roll: float = 0.0, pitch: float = 0.0) -> None:
        """Put the base at rest at (x, y, z), heading ``yaw``, tilted by ``roll`` and ``pitch``."""

    def start_height(self, ground_z: float) -> float:
        """The base's z at the start over ground at ``ground_z``."""

    def begin(self, d: mujoco.MjData) -> BodyControl:
        """The controller of one episode on ``d`` (called once the base is placed)."""

    def views(self, d: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """Live views of the base's qpos (7,) and qvel (6,) rows."""
