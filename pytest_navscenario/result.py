"""What an episode produces: the trajectory the simulation recorded, the events that ended it,
the outcome the oracle assigned and the metrics computed from them. Plain data, no logic."""
from __future__ import annotations

import enum
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from .scenario import Scenario


class Outcome(str, enum.Enum):
    """Outcome categories, in precedence order (the first that applies wins)."""
    SUBJECT_ERROR = "subject-error"  # the planner raised, returned NaN/wrong shape, or was too slow
    COLLISION = "collision"          # any robot-obstacle contact
    SAFETY_STOP = "safety-stop"      # the safety layer halted the robot
    TIMEOUT = "timeout"              # the goal was not reached in time
    SUCCESS = "success"              # goal (after all waypoints) reached within tolerance, in time

    def __str__(self) -> str:
        return self.value

    @property
    def passed(self) -> bool:
        return self is Outcome.SUCCESS


@dataclass(frozen=True)
class Collision:
    time: float
    obstacle: str          # name of the obstacle that was hit
    x: float               # contact point, world frame
    y: float
    depth: float           # penetration depth (m, >= 0)


@dataclass(frozen=True)
class SafetyStop:
    time: float
    obstacle: str          # the obstacle the predicted sweep would have hit
    speed: float           # robot speed (m/s) when halted


@dataclass(frozen=True)
class SubjectFailure:
    message: str
    tick: int
    time: float
    traceback: str | None = None   # the planner's own traceback, when it raised


@dataclass
class Trajectory:
    """Recorded states. Physics-rate arrays (every MuJoCo step, t=0 included) and tick-rate arrays."""
    t: np.ndarray            # (n,) s
    pose: np.ndarray         # (n, 3) x, y, yaw (rad), world frame
    velocity: np.ndarray     # (n, 3) vx, vy (m/s), wz (rad/s), robot frame, measured
    tick_t: np.ndarray       # (m,) s, control ticks
    command: np.ndarray      # (m, 3) commanded vx, vy, wz (robot frame) after the drive's limits
    ranges: np.ndarray       # (m, beams) float32 lidar ranges as the planner saw them (noise included)
    angles: np.ndarray       # (beams,) rad, beam directions in the robot frame
    waypoint_times: tuple[float, ...] = ()  # when each intermediate waypoint was passed

    @property
    def duration(self) -> float:
        return float(self.t[-1]) if len(self.t) else 0.0


@dataclass(frozen=True)
class Metrics:
    """Per-episode figures. Distances in m, times in s, yaw error in degrees. NaN = not defined."""
    min_clearance: float              # min distance footprint-obstacle over the run (0 on contact)
    min_clearance_obstacle: str       # which obstacle it was ("" with no obstacles)
    min_clearance_time: float
    min_clearance_x: float            # robot position at that moment
    min_clearance_y: float
    min_obstacle_gap: float           # narrowest obstacle-obstacle gap in the scenario (inf if < 2)
    min_gap_obstacles: str            # "a|b"
    path_length: float
    shortest_path_length: float       # collision-free for the footprint, through the waypoints
    path_efficiency: float            # shortest / (driven + still to go); 1 = optimal (metrics.py)
    max_deviation: float              # from the shortest path
    mean_deviation: float
    duration: float
    mean_speed: float
    goal_position_error: float
    goal_yaw_error: float             # degrees
    smoothness: float                 # mean |jerk| of the planar motion, m/s^3 (lower is smoother)
    angular_smoothness: float         # mean |angular acceleration|, rad/s^2
    reference_mean_deviation: float = float("nan")  # only with a scenario reference trajectory
    reference_max_deviation: float = float("nan")

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass
class EpisodeResult:
    """Everything one run of one scenario produced."""
    scenario: Scenario
    outcome: Outcome
    metrics: Metrics
    trajectory: Trajectory
    seed: int                                   # the episode's effective noise seed
    subject: str = ""                           # subject name (or spec)
    subject_version: str | None = None
    message: str = ""                           # one line: why this outcome
    collision: Collision | None = None
    safety_stop: SafetyStop | None = None
    subject_failure: SubjectFailure | None = None
    wall_time: float = 0.0                      # s, the whole run_scenario call
    timings: dict[str, float] = field(default_factory=dict)  # s: physics, rays, planner, harness

    @property
    def passed(self) -> bool:
        return self.outcome.passed


_TRAJ_ARRAYS = ("t", "pose", "velocity", "tick_t", "command", "ranges", "angles")


def trajectory_to_dict(traj: Trajectory) -> dict[str, Any]:
    """Plain lists (JSON / xdist-serialisable). Inverse: trajectory_from_dict."""
    out: dict[str, Any] = {name: np.asarray(getattr(traj, name)).tolist() for name in _TRAJ_ARRAYS}
    out["waypoint_times"] = list(traj.waypoint_times)
    return out


def trajectory_from_dict(data: dict[str, Any]) -> Trajectory:
    beams = len(data.get("angles", []))
    arrays = {
        "t": np.asarray(data["t"], dtype=float),
        "pose": np.asarray(data["pose"], dtype=float).reshape(-1, 3),
        "velocity": np.asarray(data["velocity"], dtype=float).reshape(-1, 3),
        "tick_t": np.asarray(data["tick_t"], dtype=float),
        "command": np.asarray(data["command"], dtype=float).reshape(-1, 3),
        "ranges": np.asarray(data["ranges"], dtype=np.float32).reshape(-1, beams),
        "angles": np.asarray(data["angles"], dtype=float),
    }
    return Trajectory(**arrays, waypoint_times=tuple(data.get("waypoint_times", ())))
