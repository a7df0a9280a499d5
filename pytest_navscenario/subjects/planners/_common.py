"""What both built-in planners read from a scenario, converted once per episode to SI units
(metres, seconds, radians): the YAML keeps yaw rates in deg/s, the planners never see degrees."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...scenario.model import Scenario


@dataclass(frozen=True)
class RobotParams:
    """The robot description a planner needs, in SI units (rad, rad/s, rad/s^2)."""
    omni: bool
    max_speed: float          # m/s
    max_lateral_speed: float  # m/s (0 for a differential drive)
    max_yaw_rate: float       # rad/s
    max_accel: float          # m/s^2
    max_yaw_accel: float      # rad/s^2
    tick: float               # s between two act() calls
    circle: bool              # footprint is a circle
    half_length: float        # m (box) or radius (circle)
    half_width: float         # m (box) or radius (circle)
    safety_margin: float      # m, the safety layer's margin (0 when disabled)
    safety_horizon: float     # s
    range_max: float          # m, lidar: a reading at or beyond this is "no return"
    goal_yaw: float           # rad
    goal_yaw_tolerance: float | None   # rad, None = heading at the goal not checked
    goal_tolerance: float     # m
    waypoint_tolerance: float  # m

    @classmethod
    def from_scenario(cls, scenario: Scenario) -> "RobotParams":
        robot, mission = scenario.robot, scenario.mission
        lim, fp = robot.limits, robot.footprint
        omni = robot.drive == "omni"
        circle = fp.shape == "circle"
        yaw_tol = mission.goal_tolerance.yaw
        return cls(
            omni=omni,
            max_speed=float(lim.max_speed),
            max_lateral_speed=float(lim.max_lateral_speed) if omni else 0.0,
            max_yaw_rate=math.radians(lim.max_yaw_rate),
            max_accel=float(lim.max_accel),
            max_yaw_accel=math.radians(lim.max_yaw_accel),
            tick=1.0 / float(scenario.simulation.control_rate),
            circle=circle,
            half_length=fp.radius if circle else fp.length / 2.0,
            half_width=fp.radius if circle else fp.width / 2.0,
            safety_margin=robot.safety.margin if robot.safety.enabled else 0.0,
            safety_horizon=robot.safety.horizon if robot.safety.enabled else 0.0,
            range_max=float(robot.lidar.range_max),
            goal_yaw=mission.goal.yaw_rad,
            goal_yaw_tolerance=None if yaw_tol is None else math.radians(yaw_tol),
            goal_tolerance=float(mission.goal_tolerance.position),
            waypoint_tolerance=float(mission.waypoint_tolerance),
        )


def wrap_angle(a):
    """Wrap an angle (or an array of angles) to [-pi, pi)."""
    return (np.asarray(a) + math.pi) % (2.0 * math.pi) - math.pi


def target_in_robot_frame(pose: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """The target point (world frame) seen from the robot: (forward, left) in metres."""
    dx = float(target[0]) - float(pose[0])
    dy = float(target[1]) - float(pose[1])
    c, s = math.cos(float(pose[2])), math.sin(float(pose[2]))
    return c * dx + s * dy, -s * dx + c * dy


def require_reset(params: RobotParams | None, planner_name: str) -> RobotParams:
    if params is None:
        raise RuntimeError(f"{planner_name}: act() called before reset(scenario); the harness "
                           f"must call reset once per episode first")
    return params
