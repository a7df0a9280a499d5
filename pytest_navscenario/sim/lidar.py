"""The planar lidar: beam directions, and one scan per control tick as a single ``mj_multiRay`` from
the robot centre at ``LIDAR_HEIGHT``, with the range noise and dropout drawn from the episode seed.

The beam tables are computed once per lidar configuration and shared read-only; a scan writes its
ranges into the episode's float32 record and hands the planner a read-only view of that row.
"""
from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from ..scenario.model import Scenario
from .world import LIDAR_HEIGHT, MODEL_CACHE_SIZE, PARTS_GROUP, TWO_PI, UNSEEN_GROUP, World


def lidar_angles(scenario: Scenario) -> np.ndarray:
    """Beam directions (rad, robot frame, counter-clockwise from the heading), read-only.

    A full circle (fov 360) has ``beams`` evenly spaced beams starting at -pi (no duplicate at +pi);
    a partial fov spans [-fov/2, +fov/2] inclusive (one beam: straight ahead).
    """
    lidar = scenario.robot.lidar
    n = int(lidar.beams)
    fov = lidar.fov_rad
    if n <= 1:
        out = np.zeros(max(n, 0))
    elif lidar.fov >= 360.0:
        out = -math.pi + TWO_PI * np.arange(n) / n
    else:
        out = np.linspace(-fov / 2.0, fov / 2.0, n)
    out.flags.writeable = False
    return out


_BEAM_TABLES: dict[Any, tuple[np.ndarray, np.ndarray]] = {}


def beam_table(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """(beam angles, their unit directions (beams, 3) in the robot frame), both read-only and
    shared by the episodes of a lidar configuration (computing them costs ~15 us per episode)."""
    lidar = scenario.robot.lidar
    table = _BEAM_TABLES.get(lidar)
    if table is None:
        angles = lidar_angles(scenario)
        dirs = np.zeros((len(angles), 3))
        dirs[:, 0] = np.cos(angles)
        dirs[:, 1] = np.sin(angles)
        dirs.flags.writeable = False
        if len(_BEAM_TABLES) >= MODEL_CACHE_SIZE:
            _BEAM_TABLES.clear()
        table = _BEAM_TABLES[lidar] = (angles, dirs)
    return table


class Lidar:
    """The episode's lidar: one ``mj_multiRay`` from the robot centre per tick, with the noise of
    the episode seed; the ranges are recorded as float32 rows and the planner gets each row as a
    read-only view (its base is read-only too, so a planner cannot make it writeable).

    Everything is computed or allocated once per episode, and a scan makes as few numpy calls as
    it can: in the loop, between MuJoCo's steps and the planner, numpy's code and data are out of
    the CPU caches and each call costs a few microseconds (profiled; several times what a tight
    benchmark of the same call says).
    """

    def __init__(self, scenario: Scenario, world: World, d: mujoco.MjData, n_rows: int, seed: int):
        lidar = scenario.robot.lidar
        angles, self.local_dirs = beam_table(scenario)
        self.angles = angles.view()              # read-only, like its base
        self.beams = beams = len(angles)
        self.rot = np.zeros((3, 3))              # world dirs = local dirs @ rot (one matmul)
        self.rot_flat = self.rot.reshape(-1)     # written through: 1-D indices are the cheapest
        self.dirs = np.zeros((beams, 3))
        self.dirs_flat = self.dirs.reshape(-1)
        self.pnt = np.array([0.0, 0.0, LIDAR_HEIGHT])
        self.geom = np.empty(beams, dtype=np.int32)
        self.dist = np.empty(beams)
        self.hit = np.empty(beams, dtype=bool)
        self.range_min, self.range_max = float(lidar.range_min), float(lidar.range_max)
        self.sigma, self.dropout = float(lidar.noise_sigma), float(lidar.dropout)
        self.per_metre, self.spurious = float(lidar.noise_per_metre), float(lidar.spurious)
        self.dropout_max = None if lidar.dropout_at_max is None else float(lidar.dropout_at_max)
        self.datasheet = bool(self.per_metre or self.spurious or self.dropout_max is not None)
        # the generator is made only when there is noise to draw (seeding it costs ~20 us)
        self.rng = (np.random.Generator(np.random.PCG64(int(seed) & 0xFFFFFFFFFFFFFFFF))
                    if self.sigma > 0.0 or self.dropout > 0.0 or self.datasheet else None)
        self.record = np.full((n_rows, beams), self.range_max, dtype=np.float32)
        self.readonly = self.record.view()
        self.readonly.flags.writeable = False
        self.model, self.data, self.body = world.model, d, world.robot_body
        # with non-convex obstacles the lidar skips their convex parts (it sees their prism mesh)
        # and obstacles the lidar cannot see (visible_to_lidar: false) are skipped altogether
        self.groups = None
        skipped = [g for g in (PARTS_GROUP, UNSEEN_GROUP) if (world.model.geom_group == g).any()]
        if skipped:
            self.groups = np.ones(6, dtype=np.uint8)
            self.groups[skipped] = 0

    def scan(self, tick: int, x: float, y: float, c: float, s: float) -> np.ndarray:
        """Ranges (read-only float32) of the robot at (x, y) with heading (cos, sin) = (c, s),
        recorded as row ``tick``; no return reads as range_max."""
        dist, rmin, rmax = self.dist, self.range_min, self.range_max
        rot = self.rot_flat
        rot[0] = rot[4] = c           # four scalar writes: cheaper than one from a nested tuple
        rot[1], rot[3] = s, -s        # (rot = [[c, s, 0], [-s, c, 0], [0, 0, 0]])
        np.dot(self.local_dirs, self.rot, out=self.dirs)
        pnt = self.pnt
        pnt[0], pnt[1] = x, y
        if self.beams:
            mujoco.mj_multiRay(self.model, self.data, pnt, self.dirs_flat, self.groups, 1, self.body,
                               self.geom, dist, None, self.beams, rmax)
        row = self.record[tick]
        if self.rng is None:
            # Without noise a beam without a return reads float32(range_max) whatever the clamp
            # does, so the row starts as that and only the hits are clamped into it (no copy of
            # range_max into the distances first: one numpy call less).
            np.greater_equal(self.geom, 0, out=self.hit)
            np.maximum(dist, rmin, out=dist)
            np.minimum(dist, rmax, out=row, where=self.hit, casting="same_kind")
        elif self.datasheet:
            self._datasheet_noise(dist, row)
        else:
            np.putmask(dist, self.geom < 0, rmax)
            if self.sigma > 0.0:
                dist += self.rng.normal(0.0, self.sigma, self.beams)
            if self.dropout > 0.0:
                np.putmask(dist, self.rng.random(self.beams) < self.dropout, rmax)
            np.maximum(dist, rmin, out=dist)
            np.minimum(dist, rmax, out=row, casting="same_kind")
        return self.readonly[tick]

    def _datasheet_noise(self, dist: np.ndarray, row: np.ndarray) -> None:
        """The datasheet model: Gaussian noise of sigma ``noise_sigma + noise_per_metre * range``,
        dropout whose probability grows linearly from ``dropout`` at 0 m to ``dropout_at_max`` at
        range_max, and spurious returns (probability ``spurious`` per beam) uniformly between
        range_min and the true range; each from the episode's generator, in that order."""
        rng, rmin, rmax = self.rng, self.range_min, self.range_max
        hit = self.geom >= 0
        np.putmask(dist, ~hit, rmax)
        true = dist.copy()
        if self.sigma > 0.0 or self.per_metre > 0.0:
            dist += rng.normal(0.0, 1.0, self.beams) * (self.sigma + self.per_metre * true)
        p = self.dropout if self.dropout_max is None else \
            self.dropout + (self.dropout_max - self.dropout) * np.minimum(true / rmax, 1.0)
        if np.any(p > 0.0):
            np.putmask(dist, rng.random(self.beams) < p, rmax)
        if self.spurious > 0.0:
            ghost = rng.random(self.beams) < self.spurious
            np.putmask(dist, ghost, rmin + rng.random(self.beams) * (np.minimum(true, rmax) - rmin))
        np.maximum(dist, rmin, out=dist)
        np.minimum(dist, rmax, out=row, casting="same_kind")

    def ranges(self, ticks: int) -> np.ndarray:
        """A copy of the first ``ticks`` recorded rows, for the Trajectory."""
        return self.record[:ticks].copy()
