"""Moving obstacles in the loop: their positions at every physics step, written into MuJoCo's mocap
bodies, and their velocities for the safety layer.

Positions come from ``scenario.motion`` (a pure function of time, so the verdict and the pictures
recompute exactly the same ones); on terrain each one's base is at its own ``z`` or, without one,
on the highest ground under its outline at that step (``scenario.ground.surface``: a person walks up a
ramp, a cart rolls off a platform's edge down onto the floor) and are computed in chunks of ``CHUNK_TICKS`` ticks in one
vectorised call per obstacle; writing a row into ``mocap_pos`` before each physics step is then one
numpy copy (the design notes measured a per-step numpy expression at ~4 us a step; a copy of a
precomputed row is a fraction of that). MuJoCo uses a mocap position from the next kinematics on:
the step's contacts and, after a tick's last ``mj_step1``, the next tick's lidar scan.
"""
from __future__ import annotations

import math

import numpy as np

from ..scenario.model import Scenario
from ..scenario.motion import Track, moving_indices
from .trajectory import Collision

CHUNK_TICKS = 64          # ticks of positions computed at once
STANDING_SPEED = 0.05     # m/s: slower (and turning slower than STANDING_YAW_RATE) is standing
STANDING_YAW_RATE = 0.1   # rad/s


class MovingObstacles:
    """The moving obstacles of one episode: ``write(i)`` puts them where they are at physics step
    ``i``; ``now(i)`` gives (indices, offsets from their scenario position, velocities) for the
    safety layer."""

    def __init__(self, scenario: Scenario, mocap_pos: np.ndarray, dt: float, spt: int):
        obstacles = scenario.obstacles
        self.indices = moving_indices(obstacles)
        self.tracks = [Track(obstacles[i]) for i in self.indices]
        self.origin = np.array([t.origin for t in self.tracks], dtype=float).reshape(-1, 2)
        self.mocap_pos = mocap_pos
        self.dt, self.spt = dt, spt
        self.rows = CHUNK_TICKS * spt + 1
        self.table = np.empty((self.rows, len(self.indices), 3))
        self.table[:, :, 2] = 0.0         # a mocap body's origin is on the floor, its geoms above it
        self.base = -self.rows        # no chunk yet
        self.scenario = scenario
        # on terrain: each obstacle's base at its own z, or on the highest ground under its outline
        self.on_ground = []           # (column, outline points (k, 2) about its centre)
        if scenario.terrain:
            from ..scenario.geometry import obstacle_polygon
            for j, i in enumerate(self.indices):
                obs = obstacles[i]
                if obs.z is not None:
                    self.table[:, j, 2] = float(obs.z)
                    continue
                outline = np.asarray(obstacle_polygon(obs).exterior.coords)[:-1] - self.origin[j]
                self.on_ground.append((j, np.vstack([outline, [(0.0, 0.0)]])))

    def _fill(self, i: int) -> None:
        """Positions for steps i .. i + rows - 1 (i is a tick's first step), and for each tick of
        the chunk what the safety layer needs, as plain floats (a Python loop over them is cheaper
        than numpy calls on a handful of obstacles)."""
        times = (i + np.arange(self.rows)) * self.dt
        for j, track in enumerate(self.tracks):
            self.table[:, j, :2] = track.positions(times)
        if self.on_ground:
            from ..scenario.ground.surface import ground_height
            for j, outline in self.on_ground:
                px = self.table[:, j, 0:1] + outline[None, :, 0]
                py = self.table[:, j, 1:2] + outline[None, :, 1]
                self.table[:, j, 2] = ground_height(self.scenario, px, py).max(axis=1)
        self.base = i
        spt = self.spt
        info = np.empty((CHUNK_TICKS, len(self.indices), 4))
        info[:, :, :2] = self.table[0:-1:spt, :, :2] - self.origin
        info[:, :, 2:] = (self.table[1::spt, :, :2] - self.table[0:-1:spt, :, :2]) / self.dt
        self.tick_info = info.tolist()

    def rows_for_tick(self, i: int) -> np.ndarray:
        """The positions (spt + 1, k, 3) of steps i .. i + spt (the tick starting at step i)."""
        if i + self.spt >= self.base + self.rows:
            self._fill(i)
        r = i - self.base
        return self.table[r:r + self.spt + 1]

    def write(self, i: int) -> None:
        """Put the obstacles where they are at step ``i`` (outside the tick loop: start)."""
        self.mocap_pos[:] = self.rows_for_tick(i)[0]

    def now(self, i: int) -> list[list[float]]:
        """Per moving obstacle (in ``indices`` order) [dx, dy, vx, vy] at step ``i`` (a tick's
        first step): its offset from its scenario x, y and its velocity (m/s) over the next step."""
        self.rows_for_tick(i)
        return self.tick_info[(i - self.base) // self.spt]


def describe_collision(collision: Collision, scenario: Scenario, qvel: np.ndarray) -> Collision:
    """The collision with who moved: the robot's speed and whether it was moving or standing (a
    robot standing still that a person walks into is a different finding from one that drives into
    a person), and the obstacle's speed at that moment."""
    speed = math.hypot(float(qvel[0]), float(qvel[1]))
    moving = speed >= STANDING_SPEED or abs(float(qvel[2])) >= STANDING_YAW_RATE
    obstacle_speed = 0.0
    for obs in scenario.obstacles:
        if obs.name == collision.obstacle and getattr(obs, "motion", None) is not None:
            obstacle_speed = math.hypot(*Track(obs).velocity(collision.time))
            break
    return Collision(collision.time, collision.obstacle, collision.x, collision.y, collision.depth,
                     robot_speed=speed, robot_moving=moving, obstacle_speed=obstacle_speed,
                     terrain=collision.terrain)
