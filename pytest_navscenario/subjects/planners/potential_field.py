"""Reactive potential-field planner (Khatib 1986), lidar-based: the weak reference subject.

The target attracts the robot with a force of constant magnitude (proportional to the
distance within ``slow_radius``); every lidar point closer than ``influence`` repels it with
Khatib's ``eta (1/d - 1/d0) / d^2``, weighted by the beam spacing so a wall pushes the same
whatever the beam count. The robot drives along the sum: forward speed from its forward
component, sideways speed (omnidirectional drive) from its lateral component, and it turns
towards it. Distances are measured from a disc of the footprint's half width, so the long
body is not accounted for in turns.

Like the paper's first planner it has the textbook weaknesses of the method (Koren and
Borenstein 1991): it hesitates or stops where the repulsion of both sides of a narrow gap
cancels the attraction (local minima), it oscillates between the walls of narrow passages,
and it cuts corners with the body it does not model. It never checks its own commands
against the safety layer. Near the goal of a mission with a yaw tolerance it turns to the
goal yaw.
"""
from __future__ import annotations

import math

import numpy as np

from ..protocol import Command, Observation
from ...scenario.model import Scenario
from ._common import RobotParams, require_reset, target_in_robot_frame, wrap_angle

REFERENCE_SPACING = 2.0 * math.pi / 72  # beam spacing the repulsion gain is expressed for


class PotentialFieldPlanner:
    """Attractive/repulsive field from lidar points.

    Parameters (keyword only):
        attraction: magnitude of the attractive force (1.0).
        slow_radius: metres from the target within which attraction fades linearly (0.5).
        repulsion: Khatib's eta, per beam at 5 degree spacing (0.06).
        influence: d0, metres beyond which a point does not repel (1.0).
        speed_gain: m/s per unit of force along the robot's axes (1.0).
        turn_gain: rad/s per radian of bearing error of the force (1.5).
    """

    name = "potential-field"
    version = "1.0"

    def __init__(self, *, attraction: float = 1.0, slow_radius: float = 0.5,
                 repulsion: float = 0.06, influence: float = 1.0, speed_gain: float = 1.0,
                 turn_gain: float = 1.5):
        self.attraction = float(attraction)
        self.slow_radius = float(slow_radius)
        self.repulsion = float(repulsion)
        self.influence = float(influence)
        self.speed_gain = float(speed_gain)
        self.turn_gain = float(turn_gain)
        self._p: RobotParams | None = None

    def reset(self, scenario: Scenario) -> None:
        self._p = RobotParams.from_scenario(scenario)
        self._angles_shape = None

    def _beams(self, angles: np.ndarray) -> None:
        self._angles_shape = angles.shape
        self._cos, self._sin = np.cos(angles), np.sin(angles)
        spacing = float(np.max(np.diff(angles))) if len(angles) > 1 else REFERENCE_SPACING
        self._weight = self.repulsion * spacing / REFERENCE_SPACING

    def act(self, obs: Observation) -> Command:
        p = require_reset(self._p, "PotentialFieldPlanner")
        if self._angles_shape != obs.angles.shape:
            self._beams(obs.angles)
        tx, ty = target_in_robot_frame(obs.pose, obs.target)
        dist = math.hypot(tx, ty)
        scale = self.attraction * min(1.0, dist / self.slow_radius) / max(dist, 1e-9)
        fx, fy = tx * scale, ty * scale

        r = obs.ranges
        d = r - p.half_width                       # from a disc of the half width
        near = np.flatnonzero((d < self.influence) & (r < p.range_max * 0.999))
        if near.size:
            dn = np.maximum(d[near], 0.02)
            mag = self._weight * (1.0 / dn - 1.0 / self.influence) / (dn * dn)
            fx -= float(mag @ self._cos[near])
            fy -= float(mag @ self._sin[near])

        if p.goal_yaw_tolerance is not None and not len(obs.waypoints) and dist < p.goal_tolerance * 0.6:
            bearing = float(wrap_angle(p.goal_yaw - float(obs.pose[2])))
        else:
            bearing = math.atan2(fy, fx)
        vx = min(max(self.speed_gain * fx, 0.0), p.max_speed)
        vy = min(max(self.speed_gain * fy, -p.max_lateral_speed), p.max_lateral_speed)
        wz = min(max(self.turn_gain * bearing, -p.max_yaw_rate), p.max_yaw_rate)
        return Command(vx, vy, wz)
