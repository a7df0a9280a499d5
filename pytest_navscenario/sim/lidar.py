"""The planar lidar: beam directions, and one scan per control tick as a single ``mj_multiRay`` from
the robot centre at ``lidar.mount_height`` (``LIDAR_HEIGHT`` by default), with the range noise and
dropout drawn from the episode seed.

On a body that rides the ground the scan plane is the body's: ``scan_posed`` casts from the mount
point on the tilted base along the base's own plane, so a ramp ahead reads as a wall, a drop-off is
invisible and a step below the plane is unseen (the realism of a 2D lidar on real terrain). Rough
ground and heightfields are cast by ``hfield_rays`` (``mj_multiRay`` skips their geom group).

The beam tables are computed once per lidar configuration and shared read-only; a scan writes its
ranges into the episode's float32 record and hands the planner a read-only view of that row.
"""
from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from ..scenario.model import Scenario
from .ground.heightfield import HFIELD_GROUP, placed_grids
from .ground.hfield_rays import cast_grids
from .world import MODEL_CACHE_SIZE, TWO_PI, World


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


def lidar_mask(world: World, grids: bool) -> np.ndarray | None:
    """The geom groups ``mj_multiRay`` casts against: the world's lidar mask, and without the
    heightfields' group when the lidar casts against the grids itself (``grids``)."""
    if not grids:
        return world.lidar_groups
    groups = np.ones(6, dtype=np.uint8) if world.lidar_groups is None else world.lidar_groups.copy()
    groups[HFIELD_GROUP] = 0
    groups.flags.writeable = False
    return groups


def grid_hits(grids: tuple, pnt: np.ndarray, dirs: np.ndarray, rmax: float, geom: np.ndarray,
              dist: np.ndarray) -> None:
    """Lower ``mj_multiRay``'s results (``geom`` < 0: no hit) where a beam meets one of the
    ``grids`` nearer; such a beam's geom becomes ``HFIELD_HIT``."""
    met = np.where(geom >= 0, dist, np.inf)
    hf = cast_grids(grids, pnt, dirs, rmax, within=met)
    nearer = hf < met
    if nearer.any():
        dist[nearer] = hf[nearer]
        geom[nearer] = HFIELD_HIT


HFIELD_HIT = 1 << 30     # the geom id recorded for a beam that met a height grid (any id >= 0 is a hit)


def datasheet_noise(rng: np.random.Generator, dist: np.ndarray, hit: np.ndarray, rmin: float, rmax: float,
                    sigma: float, per_metre: float, dropout: float, dropout_max: float | None,
                    spurious: float, out: np.ndarray) -> np.ndarray | None:
    """The lidars' datasheet noise model, from ``dist`` (changed) into ``out``: a beam without a
    return (``hit`` False) reads range_max, then Gaussian noise of sigma ``sigma + per_metre *
    range``, dropout whose probability grows linearly from ``dropout`` at 0 m to ``dropout_max`` at
    range_max (constant ``dropout`` when None), and spurious returns (probability ``spurious`` per
    beam) uniformly between range_min and the true range; each from ``rng``, in that order; the
    result clamped to [range_min, range_max]. Returns the spurious beams' mask (None: none drawn)."""
    n = len(dist)
    np.putmask(dist, ~hit, rmax)
    true = dist.copy()
    if sigma > 0.0 or per_metre > 0.0:
        dist += rng.normal(0.0, 1.0, n) * (sigma + per_metre * true)
    p = dropout if dropout_max is None else dropout + (dropout_max - dropout) * np.minimum(true / rmax, 1.0)
    if np.any(p > 0.0):
        np.putmask(dist, rng.random(n) < p, rmax)
    ghost = None
    if spurious > 0.0:
        ghost = rng.random(n) < spurious
        np.putmask(dist, ghost, rmin + rng.random(n) * (np.minimum(true, rmax) - rmin))
    np.maximum(dist, rmin, out=dist)
    np.minimum(dist, rmax, out=out, casting="same_kind")
    return ghost


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
        self.pnt = np.array([0.0, 0.0, float(lidar.mount_height)])
        self.mount = float(lidar.mount_height)
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
        self.grids = placed_grids(scenario)       # rough ground and heightfields: cast by hfield_rays
        self.groups = lidar_mask(world, bool(self.grids))   # convex parts, unseen obstacles skipped

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
        return self._record(tick, dist, rmin, rmax)

    def scan_posed(self, tick: int, origin: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """Ranges (read-only float32) of the lidar at ``origin`` (world frame) in the plane of a
        base turned by ``rot`` (3 x 3, world from base), recorded as row ``tick``: the scan of a
        body that rides the ground, tilted with it. ``sensor_origin`` gives the origin."""
        np.dot(self.local_dirs, rot.T, out=self.dirs)
        dist, rmax = self.dist, self.range_max
        if self.beams:
            mujoco.mj_multiRay(self.model, self.data, origin, self.dirs_flat, self.groups, 1, self.body,
                               self.geom, dist, None, self.beams, rmax)
            if self.grids:
                grid_hits(self.grids, origin, self.dirs, rmax, self.geom, dist)
        return self._record(tick, dist, self.range_min, rmax)

    def _record(self, tick: int, dist: np.ndarray, rmin: float, rmax: float) -> np.ndarray:
        """The scan's ranges into row ``tick``, with the noise; the planner's read-only view."""
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
        """The datasheet model (``datasheet_noise``) into ``row``."""
        datasheet_noise(self.rng, dist, self.geom >= 0, self.range_min, self.range_max, self.sigma,
                        self.per_metre, self.dropout, self.dropout_max, self.spurious, row)

    def ranges(self, ticks: int) -> np.ndarray:
        """A copy of the first ``ticks`` recorded rows, for the Trajectory."""
        return self.record[:ticks].copy()


def sensor_origin(pos: np.ndarray, rot: np.ndarray, offset: tuple[float, float, float]) -> np.ndarray:
    """The world point of a sensor mounted at ``offset`` (base frame) on a base at ``pos`` turned by
    ``rot`` (world from base)."""
    return pos + rot @ np.asarray(offset, dtype=float)


def base_rotation(quat: np.ndarray) -> np.ndarray:
    """The 3 x 3 rotation (world from base) of a base's unit quaternion (w, x, y, z)."""
    out = np.empty(9)
    mujoco.mju_quat2Mat(out, np.asarray(quat, dtype=float))
    return out.reshape(3, 3)
