"""A user's own planner, as a package outside pytest-navscenario: drive to the next waypoint,
pushed away from close lidar returns (a small reactive planner for omnidirectional robots).

Run the example scenarios against it from the project root::

    pytest examples/scenarios --nav-subject=examples.mynav:Planner

The harness calls ``Planner()`` once per episode, then ``reset(scenario)`` and ``act(obs)`` per
tick (angles in radians; see pytest_navscenario/planner.py).
"""
from __future__ import annotations

import math

import numpy as np


class Planner:
    name = "mynav"
    version = "1.0"

    def __init__(self, cruise: float = 0.8, influence: float = 1.2, push: float = 0.6):
        self.cruise = cruise          # m/s wanted speed
        self.influence = influence    # m: lidar returns closer than this push the robot away
        self.push = push              # strength of the push
        self.max_speed = cruise

    def reset(self, scenario) -> None:
        self.max_speed = min(self.cruise, scenario.robot.limits.max_speed)

    def act(self, obs):
        x, y, yaw = (float(v) for v in obs.pose)
        tx, ty = (float(v) for v in obs.target)
        dx, dy = tx - x, ty - y
        c, s = math.cos(yaw), math.sin(yaw)
        gx, gy = c * dx + s * dy, -s * dx + c * dy          # target in the robot frame
        dist = math.hypot(gx, gy)
        speed = min(self.max_speed, dist)
        vx, vy = (gx / dist * speed, gy / dist * speed) if dist > 1e-6 else (0.0, 0.0)
        near = obs.ranges < self.influence
        if np.any(near):
            r = np.maximum(obs.ranges[near].astype(float), 0.05)
            weight = self.push * (1.0 / r - 1.0 / self.influence)
            vx -= float(np.sum(weight * np.cos(obs.angles[near])))
            vy -= float(np.sum(weight * np.sin(obs.angles[near])))
        norm = math.hypot(vx, vy)
        if norm > self.max_speed:
            vx, vy = vx / norm * self.max_speed, vy / norm * self.max_speed
        return vx, vy, 0.0
