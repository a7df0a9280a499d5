"""What the simulation records during an episode: the trajectory and the events that ended it
(collision, safety stop, subject failure). Plain data, written by the control loop and read by
the verdict."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Collision:
    time: float
    obstacle: str          # name of the obstacle that was hit
    x: float               # contact point, world frame
    y: float
    depth: float           # penetration depth (m, >= 0)
    robot_speed: float = 0.0      # m/s, the robot's speed at the contact
    robot_moving: bool = True     # False: the robot stood still and was hit (sim/moving.py)
    obstacle_speed: float = 0.0   # m/s, the obstacle's speed at the contact (0: static)
    terrain: bool = False         # True: the chassis hit a terrain face ("obstacle" names the element)


@dataclass(frozen=True)
class SafetyStop:
    time: float
    obstacle: str          # the obstacle the predicted sweep would have hit ("" for the ground)
    speed: float           # robot speed (m/s) when halted
    ground: str = ""       # the ground it would have driven into, as a phrase ("a drop of 0.50 m
                           # ahead"): the ground layer (sim/ground/ground_safety.py) of a 3D lidar
    yaw_rate: float = 0.0  # rad/s when halted: a robot turning in place has speed 0 and still sweeps


@dataclass(frozen=True)
class TerrainEvent:
    """The robot lost its footing or could not go on over the terrain: ``kind`` "fell" (off an edge
    or into a hole: ``drop`` metres), "tipped" (roll or pitch past the body's limit) or "stuck"
    (driven but not moving: ``detail`` says what held it) or "still" (driven on level ground
    without moving at all: nothing of the terrain held it, its drive did not follow). ``element`` names the terrain element
    ("platform 'dock'"; "" on the plain floor); (x, y, z) is where the base was."""
    kind: str
    time: float
    element: str
    x: float
    y: float
    z: float
    drop: float = 0.0          # m, fell
    roll: float = 0.0          # degrees, at the event
    pitch: float = 0.0         # degrees
    detail: str = ""


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
    believed: np.ndarray | None = None      # (m, 3) the pose the planner believed at each tick (drift)
    # a body that rides the ground (None for the planar body): physics-rate base height (m) and
    # attitude (rad) of the chassis
    z: np.ndarray | None = None             # (n,)
    roll: np.ndarray | None = None          # (n,)
    pitch: np.ndarray | None = None         # (n,)
    cloud: np.ndarray | None = None         # (m, rings, beams) float32 3D lidar ranges (robot.lidar3d),
                                            # no return = its range_max; None without one

    @property
    def duration(self) -> float:
        return float(self.t[-1]) if len(self.t) else 0.0

    @classmethod
    def empty(cls) -> "Trajectory":
        """No states: what a result carries when its trajectory was not kept (payloads, workers)."""
        return cls(t=np.zeros(0), pose=np.zeros((0, 3)), velocity=np.zeros((0, 3)), tick_t=np.zeros(0),
                   command=np.zeros((0, 3)), ranges=np.zeros((0, 0), dtype=np.float32), angles=np.zeros(0))


_TRAJ_ARRAYS = ("t", "pose", "velocity", "tick_t", "command", "ranges", "angles")
_ATTITUDE = ("z", "roll", "pitch")


def trajectory_to_dict(traj: Trajectory, *, cloud: bool = False) -> dict[str, Any]:
    """Plain lists (JSON / xdist-serialisable). Inverse: trajectory_from_dict. ``cloud``: with the
    3D lidar's ranges, as base64 float32 (a list would be ten times the size)."""
    out: dict[str, Any] = {name: np.asarray(getattr(traj, name)).tolist() for name in _TRAJ_ARRAYS}
    out["waypoint_times"] = list(traj.waypoint_times)
    if traj.believed is not None:
        out["believed"] = np.asarray(traj.believed).tolist()
    for name in _ATTITUDE:
        value = getattr(traj, name)
        if value is not None:
            out[name] = np.asarray(value).tolist()
    if cloud and traj.cloud is not None:
        import base64
        data = np.ascontiguousarray(traj.cloud, dtype="<f4")
        out["cloud"] = {"shape": list(data.shape), "float32": base64.b64encode(data.tobytes()).decode("ascii")}
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
    believed = data.get("believed")
    attitude = {name: np.asarray(data[name], dtype=float) for name in _ATTITUDE if data.get(name) is not None}
    cloud = data.get("cloud")
    if cloud is not None:
        import base64
        cloud = np.frombuffer(base64.b64decode(cloud["float32"]), dtype="<f4").reshape(cloud["shape"]).copy()
    return Trajectory(**arrays, waypoint_times=tuple(data.get("waypoint_times", ())),
                      believed=None if believed is None else np.asarray(believed, dtype=float).reshape(-1, 3),
                      cloud=cloud, **attitude)
