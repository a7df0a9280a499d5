"""Projecting scans and clouds: every return into the world frame with the robot's pose at the scan's time,
accumulated per grid cell (memory for the grid, not for every return)."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .reading import BagData


def poses_at(data: BagData, t: np.ndarray) -> np.ndarray:
    """The robot's poses (k, 3) x, y, yaw in the world frame at times ``t``, interpolated."""
    od = data.odom
    yaw = np.unwrap(od[:, 3])
    return np.stack([np.interp(t, od[:, 0], od[:, 1]), np.interp(t, od[:, 0], od[:, 2]),
                     np.interp(t, od[:, 0], yaw)], axis=1)


def project_scans(data: BagData, mount: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Every valid return as a point in the odometry frame, and the laser position it was seen from."""
    poses = poses_at(data, data.scan_t)
    rng = data.scan_ranges.astype(float)
    valid = np.isfinite(rng) & (rng > data.range_min) & (rng < data.range_max * 0.99)
    rng = np.where(valid, rng, 0.0)
    mx, my, myaw = mount
    ang = data.scan_angles[None, :] + myaw
    lx = mx + rng * np.cos(ang)
    ly = my + rng * np.sin(ang)
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    wx = poses[:, 0:1] + c * lx - s * ly
    wy = poses[:, 1:2] + s * lx + c * ly
    ox = poses[:, 0] + np.cos(poses[:, 2]) * mx - np.sin(poses[:, 2]) * my
    oy = poses[:, 1] + np.sin(poses[:, 2]) * mx + np.cos(poses[:, 2]) * my
    origin = np.broadcast_to(np.stack([ox, oy], 1)[:, None, :], wx.shape + (2,))
    return np.stack([wx[valid], wy[valid]], 1), origin[valid]



@dataclass
class Grid:
    """Returns accumulated per grid cell: the cell's mean return and mean viewpoint, and hits;
    for 3D returns also the highest point above the ground seen in the cell (NaN for 2D scans)."""
    means: np.ndarray    # (k, 4) x, y of the returns, x, y of the laser that saw them
    counts: np.ndarray   # (k,) returns per cell
    returns: int         # returns in total
    top: np.ndarray | None = None   # (k,) m above the ground, or None (2D scans)


class GridAccumulator:
    """Sums returns per cell batch by batch, merging every ``merge_every`` batches, so memory
    follows the area seen, not the length of the bag. Cells are keyed by one int64 (column
    * 2^32 + row): only their sums are kept, never their coordinates."""

    def __init__(self, res: float, merge_every: int = 64):
        self.res, self.merge_every = res, merge_every
        self.parts: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
        self.returns = 0
        self.has_height = False

    def add(self, points: np.ndarray, origins: np.ndarray, heights: np.ndarray | None = None) -> None:
        self.returns += len(points)
        if not len(points):
            return
        self.has_height |= heights is not None
        cells = np.floor(points / self.res).astype(np.int64)
        keys, inverse = np.unique(cells[:, 0] * 4294967296 + cells[:, 1], return_inverse=True)
        self.parts.append(_reduce(keys, inverse.reshape(-1), np.concatenate([points, origins], axis=1),
                                  np.ones(len(points), np.int64), heights))
        if len(self.parts) >= self.merge_every:
            self.parts = [self._merged()]

    def _merged(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        if len(self.parts) == 1:
            return self.parts[0]
        keys, inverse = np.unique(np.concatenate([p[0] for p in self.parts]), return_inverse=True)
        return _reduce(keys, inverse.reshape(-1), np.concatenate([p[1] for p in self.parts]),
                       np.concatenate([p[2] for p in self.parts]), np.concatenate([p[3] for p in self.parts]))

    def grid(self) -> Grid:
        if not self.parts:
            return Grid(np.zeros((0, 4)), np.zeros(0, np.int64), self.returns)
        _, sums, counts, top = self._merged()
        return Grid(means=sums / counts[:, None], counts=counts, returns=self.returns,
                    top=np.where(np.isfinite(top), top, np.nan) if self.has_height else None)


def _reduce(keys: np.ndarray, inverse: np.ndarray, values: np.ndarray, counts: np.ndarray,
            heights: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per key: the sums of ``values`` columns, the sum of ``counts``, the max of ``heights``."""
    n = len(keys)
    sums = np.stack([np.bincount(inverse, weights=values[:, j], minlength=n) for j in range(values.shape[1])], 1)
    total = np.bincount(inverse, weights=counts, minlength=n).astype(np.int64)
    top = np.full(n, -np.inf)
    if heights is not None:
        np.maximum.at(top, inverse, heights)
    return keys, sums, total, top


def grid_returns(data: BagData, mount: tuple[float, float, float], res: float = 0.05,
                 chunk: int = 1000) -> Grid:
    """Project the scans ``chunk`` at a time and sum them per cell, so an hour-long bag needs
    memory for its grid, not for every return at once."""
    acc = GridAccumulator(res)
    for i in range(0, len(data.scan_t), chunk):
        sub = dataclasses.replace(data, scan_t=data.scan_t[i:i + chunk], scan_ranges=data.scan_ranges[i:i + chunk])
        acc.add(*project_scans(sub, mount))
    return acc.grid()
