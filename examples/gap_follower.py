"""A follow-the-gap planner: a competent reactive planner the search was never tuned on.

Use it as a subject: ``pytest --nav-subject examples.gap_follower:FollowTheGap`` or
``python benchmarks/bench_search.py --subject examples.gap_follower:FollowTheGap``.

Each tick: every lidar return is widened by the robot's half width plus a margin (a beam is
blocked if a return lies within that radius of the straight line the beam describes, out to a
look-ahead distance); among the free beams pick the one closest in angle to the target, turn
toward it and drive at a speed that falls with the free distance ahead. With no free beam it
turns in place toward the most open direction. Works from the lidar alone (no map).
"""
from __future__ import annotations

import math

import numpy as np


class FollowTheGap:
    name = "follow-the-gap"
    version = "1.0"

    def __init__(self, margin: float = 0.15, lookahead: float = 2.0, speed: float = 0.8):
        self.margin, self.lookahead, self.speed = margin, lookahead, speed
        self.half_width = 0.3
        self.half_length = 0.45

    def reset(self, scenario) -> None:
        fp = scenario.robot.footprint
        if fp.shape == "circle":
            self.half_width = self.half_length = fp.radius
        else:
            self.half_width, self.half_length = fp.width / 2, fp.length / 2

    def act(self, obs):
        x, y, yaw = (float(v) for v in obs.pose)
        tx, ty = (float(v) for v in obs.target)
        goal_dist = math.hypot(tx - x, ty - y)
        bearing = math.atan2(ty - y, tx - x) - yaw
        bearing = (bearing + math.pi) % (2 * math.pi) - math.pi
        ranges = np.asarray(obs.ranges, dtype=float)
        angles = np.asarray(obs.angles, dtype=float)
        px, py = ranges * np.cos(angles), ranges * np.sin(angles)       # returns, robot frame
        radius = self.half_width + self.margin
        reach = min(self.lookahead, goal_dist + self.half_length)
        free = np.empty(len(angles), dtype=bool)
        clear_ahead = np.empty(len(angles))
        for k, a in enumerate(angles):                                   # 36-360 beams: cheap enough
            c, s = math.cos(a), math.sin(a)
            along = px * c + py * s
            side = np.abs(-px * s + py * c)
            hit = (along > 0) & (side < radius)
            first = float(along[hit].min()) if hit.any() else math.inf
            clear_ahead[k] = first
            free[k] = first > reach
        if free.any():
            diff = np.abs((angles - bearing + math.pi) % (2 * math.pi) - math.pi)
            diff[~free] = math.inf
            k = int(np.argmin(diff))
        else:
            k = int(np.argmax(clear_ahead))
        heading = float((angles[k] + math.pi) % (2 * math.pi) - math.pi)
        ahead = clear_ahead[int(np.argmin(np.abs(angles)))]
        v = self.speed * min(1.0, max(0.0, (ahead - self.half_length - 0.1) / self.lookahead))
        v *= max(0.0, math.cos(heading)) ** 2
        if goal_dist < 0.5:
            v = min(v, goal_dist)
        return (v, 0.0, max(-1.5, min(1.5, 2.0 * heading)))
