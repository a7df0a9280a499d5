"""The 3D lidar: a spinning multi-ring lidar (``robot.lidar3d``) whose point cloud is part of the
observation.

Beams: ``rings`` rings evenly from ``fov_low`` to ``fov_high`` degrees of elevation (one ring:
level), ``beams`` beams a ring over 360 degrees starting behind the sensor as the 2D lidar's (-pi,
counter-clockwise), in the sensor's own frame (x forward, z up). The sensor is mounted at
(``mount_x``, ``mount_y``, ``mount_z``) on the base, pitched down by ``mount_pitch`` degrees; on a
body that rides the ground it tilts with the base.

A scan is one ``mj_multiRay`` from the sensor (all beams share its origin: MuJoCo culls geoms by
their angular extent) against every geom but the robot's own, the convex parts of non-convex
obstacles, obstacles with ``visible_to_lidar: false`` and height grids, which ``hfield_rays``
casts instead. The ranges get the 2D lidar's noise models (``noise_sigma``, ``dropout``,
``noise_per_metre``, ``dropout_at_max``, ``spurious``), drawn from a generator of the episode seed
of their own (the 2D lidar's draws are unchanged by a 3D lidar). Ranges are recorded (rings,
beams) per tick, no return as ``range_max``; the planner gets the returns as points (N x 3,
float32, sensor frame, read-only), ring by ring.
"""
from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from ..scenario.model import Scenario
from .ground.heightfield import placed_grids
from .lidar import datasheet_noise, grid_hits, lidar_mask
from .world import World

SEED_STREAM = 3          # the 3D lidar's generator: SeedSequence([seed, SEED_STREAM])
LEVEL = np.zeros(2)      # the attitude (roll, pitch) of a base that never tilts (the planar body)
LEVEL.flags.writeable = False


def ring_elevations(spec: Any) -> np.ndarray:
    """Elevation of each ring (rad), lowest first: evenly from fov_low to fov_high inclusive."""
    if spec.rings <= 1:
        return np.zeros(max(int(spec.rings), 0))
    return np.radians(np.linspace(spec.fov_low, spec.fov_high, int(spec.rings)))


def beam_azimuths(spec: Any) -> np.ndarray:
    """Azimuth of each beam of a ring (rad, counter-clockwise from the sensor's x axis), from -pi."""
    n = int(spec.beams)
    return -math.pi + 2.0 * math.pi * np.arange(n) / n


def sensor_directions(spec: Any) -> np.ndarray:
    """Unit beam directions (rings * beams, 3) in the sensor frame, ring-major (ring r, beam b at
    row r * beams + b)."""
    e = ring_elevations(spec)[:, None]
    a = beam_azimuths(spec)[None, :]
    dirs = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e) * np.ones_like(a)], axis=-1)
    return dirs.reshape(-1, 3)


def mount_rotation(spec: Any) -> np.ndarray:
    """Base from sensor: the sensor pitched down by ``mount_pitch`` degrees about its y axis."""
    p = math.radians(spec.mount_pitch)
    c, s = math.cos(p), math.sin(p)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


_TABLES: dict[Any, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def beam_table(spec: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(directions in the sensor frame, in the base frame, the mount offset), read-only, shared by
    the episodes of a 3D lidar configuration."""
    table = _TABLES.get(spec)
    if table is None:
        local = sensor_directions(spec)
        base = local @ mount_rotation(spec).T
        offset = np.array([spec.mount_x, spec.mount_y, spec.mount_z], dtype=float)
        for a in (local, base, offset):
            a.flags.writeable = False
        if len(_TABLES) >= 64:
            _TABLES.clear()
        table = _TABLES[spec] = (local, base, offset)
    return table


class CloudLidar:
    """The episode's 3D lidar: ``scan`` casts from the sensor on the base's pose, records the
    ranges (float32, no return = range_max) and returns the points the planner sees."""

    def __init__(self, scenario: Scenario, world: World, d: mujoco.MjData, n_rows: int, seed: int):
        spec = scenario.robot.lidar3d
        self.spec = spec
        self.local_dirs, self.base_dirs, self.offset = beam_table(spec)
        self.rings, self.per_ring = int(spec.rings), int(spec.beams)
        self.n = n = len(self.local_dirs)
        self.dirs = np.empty((n, 3))
        self.dirs_flat = self.dirs.reshape(-1)
        self.geom = np.empty(n, dtype=np.int32)
        self.dist = np.empty(n)
        self.range_min, self.range_max = float(spec.range_min), float(spec.range_max)
        self.sigma, self.dropout = float(spec.noise_sigma), float(spec.dropout)
        self.per_metre, self.spurious = float(spec.noise_per_metre), float(spec.spurious)
        self.dropout_max = None if spec.dropout_at_max is None else float(spec.dropout_at_max)
        noisy = self.sigma > 0 or self.dropout > 0 or self.per_metre > 0 or self.spurious > 0 \
            or self.dropout_max is not None
        self.rng = (np.random.Generator(np.random.PCG64(np.random.SeedSequence([int(seed) & (2 ** 64 - 1),
                                                                                SEED_STREAM])))
                    if noisy else None)
        # rows are written whole, tick by tick: np.empty touches no memory until then
        self.record = np.empty((n_rows, self.rings, self.per_ring), dtype=np.float32)
        self.model, self.data, self.body = world.model, d, world.robot_body
        self.grids = placed_grids(scenario)
        self.groups = lidar_mask(world, bool(self.grids))
        self.ticks = 0

    def origin(self, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """The sensor's world position on a base at ``pos`` turned by ``rot`` (world from base)."""
        return pos + rot @ self.offset

    def scan(self, tick: int, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """The points (N x 3, float32, sensor frame, read-only) seen from a base at ``pos`` (world
        frame, the base's origin) turned by ``rot`` (3 x 3, world from base); the ranges are
        recorded as row ``tick``."""
        origin = pos + rot @ self.offset
        self.last_origin = origin
        np.dot(self.base_dirs, rot.T, out=self.dirs)
        dist, geom, rmax = self.dist, self.geom, self.range_max
        if self.n:
            mujoco.mj_multiRay(self.model, self.data, origin, self.dirs_flat, self.groups, 1, self.body,
                               geom, dist, None, self.n, rmax)
            if self.grids:
                grid_hits(self.grids, origin, self.dirs, rmax, geom, dist)
        ranges = self._noisy(dist, geom >= 0)
        self.record[tick] = ranges.reshape(self.rings, self.per_ring)
        self.ticks = max(self.ticks, tick + 1)
        seen = ranges < rmax
        self.last_seen, self.last_ranges = seen, ranges
        points = (self.local_dirs[seen] * ranges[seen, None]).astype(np.float32)
        points.flags.writeable = False
        return points

    def world_points(self) -> np.ndarray:
        """The last scan's returns in the world frame (N x 3, float64), as its beams flew."""
        seen = self.last_seen
        return self.last_origin + self.dirs[seen] * self.last_ranges[seen, None]

    def _noisy(self, dist: np.ndarray, hit: np.ndarray) -> np.ndarray:
        """The ranges the beams read (float32, no return = range_max): the 2D lidar's noise models
        (``lidar.datasheet_noise``), except that a beam without a return stays without one unless
        it drew a spurious return (noise on range_max would be a point that is not there)."""
        out = np.empty(self.n, dtype=np.float32)
        if self.rng is None:
            np.putmask(dist, ~hit, self.range_max)
            np.clip(dist, self.range_min, self.range_max, out=dist)
            out[:] = dist
            return out
        ghost = datasheet_noise(self.rng, dist, hit, self.range_min, self.range_max, self.sigma,
                                self.per_metre, self.dropout, self.dropout_max, self.spurious, out)
        miss = ~hit if ghost is None else ~hit & ~ghost
        out[miss] = self.range_max
        return out

    def ranges(self, ticks: int) -> np.ndarray:
        """The first ``ticks`` recorded scans (ticks, rings, beams), for the Trajectory."""
        return self.record[:ticks].copy()
