"""One episode's draw of a scenario's opt-in perturbations (``simulation.perturb``): the start
pose moved a little, moving obstacles started a little earlier or later.

A pure function of the scenario and the episode's noise seed (its own stream, apart from the
lidar's and the drift's), so a run is repeatable and two seeds differ. The harness runs, judges
and measures the perturbed scenario (the verdict recomputes moving obstacles' positions from it,
so they agree with what was simulated) and reports the scenario as written.
"""
from __future__ import annotations

import dataclasses
import random

from .model import Scenario

TRIES = (1.0, 0.5, 0.25)   # a start drawn onto an obstacle is drawn again this much nearer, then not moved


def perturbed(scenario: Scenario, seed: int) -> Scenario:
    """``scenario`` with this episode's perturbation applied (itself when it opts into none)."""
    per = scenario.simulation.perturb
    if not per.any:
        return scenario
    rnd = random.Random(f"navscenario-perturb:{int(seed)}")
    dx, dy, dyaw = (rnd.uniform(-1.0, 1.0) for _ in range(3))
    shifts = [rnd.uniform(-1.0, 1.0) for _ in scenario.obstacles]   # one per obstacle: stable streams
    out = scenario
    start = scenario.mission.start
    if per.start_xy or per.start_yaw:
        for scale in TRIES:
            pose = dataclasses.replace(start, x=start.x + scale * dx * per.start_xy,
                                       y=start.y + scale * dy * per.start_xy, yaw=start.yaw + scale * dyaw * per.start_yaw)
            if _clear(scenario, pose):
                out = dataclasses.replace(out, mission=dataclasses.replace(out.mission, start=pose))
                break
    if per.motion_time:
        obstacles = []
        for obs, shift in zip(scenario.obstacles, shifts):
            motion = getattr(obs, "motion", None)
            if motion is not None:
                obs = dataclasses.replace(obs, motion=dataclasses.replace(
                    motion, start=max(0.0, motion.start + shift * per.motion_time)))
            obstacles.append(obs)
        out = dataclasses.replace(out, obstacles=tuple(obstacles))
    return out


def _clear(scenario: Scenario, pose) -> bool:
    """Whether the robot's footprint at ``pose`` touches no obstacle (where it stands at t = 0)."""
    import math

    from .geometry import footprint_polygon, obstacle_polygon

    robot = footprint_polygon(scenario.robot.footprint, pose.x, pose.y, math.radians(pose.yaw))
    return not any(robot.intersects(obstacle_polygon(obs)) for obs in scenario.obstacles)
