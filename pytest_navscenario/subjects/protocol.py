"""The planner protocol: what a subject under test sees each tick and what it must answer.

A planner is any object with::

    reset(self, scenario: Scenario) -> None        # once per episode, before the first tick
    act(self, obs: Observation) -> Command          # once per control tick

and optionally ``name`` / ``version`` string attributes (copied into the results file).
Angles here are in **radians** (YAML scenarios use degrees; see the scenario model).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, NamedTuple, Protocol, runtime_checkable

from ..scenario.model import Obstacle, Scenario

if TYPE_CHECKING:  # numpy is not imported at plugin load: only episodes need it
    import numpy as np


class Command(NamedTuple):
    """Velocity command in the robot frame: vx forward (m/s), vy left (m/s), wz (rad/s).

    A differential-drive robot cannot move sideways: its ``vy`` is ignored by the drive.
    A planner may also return any length-3 sequence of finite floats.
    """
    vx: float
    vy: float = 0.0
    wz: float = 0.0


@dataclass(frozen=True)
class Observation:
    """What the planner sees at one control tick (arrays are read-only)."""
    tick: int                     # 0, 1, 2, ...
    time: float                   # s since the episode started
    pose: np.ndarray              # (3,) x, y (m), yaw (rad) in the world frame
    velocity: np.ndarray          # (3,) vx, vy (m/s), wz (rad/s) in the robot frame, measured
    ranges: np.ndarray            # (beams,) m; no return reads as lidar.range_max
    angles: np.ndarray            # (beams,) rad, beam directions in the robot frame
    goal: np.ndarray              # (3,) x, y, yaw (rad) of the final goal
    waypoints: np.ndarray         # (k, 2) remaining intermediate waypoints, in order (k may be 0)
    obstacles: tuple[Obstacle, ...]  # static map, for planners that use one (YAML units)
    # Added with terrain (issue 25); planners that ignore them work as before.
    points: np.ndarray | None = None  # (N, 3) float32 3D lidar returns (m) in the sensor's frame
                                      # (x forward, z up; robot.lidar3d's mount), ring by ring; None
                                      # without robot.lidar3d
    attitude: np.ndarray | None = None  # (2,) roll, pitch (rad) of the robot's base (an IMU; pitch
                                        # positive nose down); (0, 0) for the planar body

    @property
    def target(self) -> np.ndarray:
        """The next point to drive to: the first remaining waypoint, else the goal position."""
        return self.waypoints[0] if len(self.waypoints) else self.goal[:2]


@runtime_checkable
class Planner(Protocol):
    def reset(self, scenario: Scenario) -> None: ...

    def act(self, obs: Observation) -> Any: ...


PlannerFactory = Callable[[], Planner]
