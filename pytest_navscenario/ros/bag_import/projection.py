"""Projecting scans: every return into the world frame with the robot's pose at the scan's time,
accumulated per grid cell (memory for the grid, not for every return)."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .reading import BagData


def _poses_at(data: BagData, t: np.ndarray) -> np.ndarray:
    od = data.odom
    yaw = np.unwrap(od[:, 3])
    return np.stack([np.interp(t, od[:, 0], od[:, 1]), np.interp(t, od[:, 0], od[:, 2]),
                     np.interp(t, od[:, 0], yaw)], axis=1)


def project_scans(data: BagData, mount: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Every valid return as a point in the odometry frame, and the laser position it was seen from."""
    poses = _poses_at(data, data.scan_t)
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
    """Returns accumulated per grid cell: the cell's mean return and mean viewpoint, and hits."""
    means: np.ndarray    # (k, 4) x, y of the returns, x, y of the laser that saw them
    counts: np.ndarray   # (k,) returns per cell
    returns: int         # returns in total


def _cells(points: np.ndarray, origins: np.ndarray, res: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(cell keys (k, 2), sums of [point, origin] (k, 4), counts (k,)) of a batch of returns."""
    cells = np.floor(points / res).astype(np.int64)
    keys, inverse, counts = np.unique(cells, axis=0, return_inverse=True, return_counts=True)
    sums = np.zeros((len(keys), 4))
    np.add.at(sums, inverse.reshape(-1), np.concatenate([points, origins], axis=1))
    return keys, sums, counts


def grid_returns(data: BagData, mount: tuple[float, float, float], res: float = 0.05,
                 chunk: int = 1000) -> Grid:
    """Project the scans ``chunk`` at a time and sum them per cell, so an hour-long bag needs
    memory for its grid, not for every return at once."""
    parts = []
    total = 0
    for i in range(0, len(data.scan_t), chunk):
        sub = dataclasses.replace(data, scan_t=data.scan_t[i:i + chunk], scan_ranges=data.scan_ranges[i:i + chunk])
        pts, origins = project_scans(sub, mount)
        total += len(pts)
        if len(pts):
            parts.append(_cells(pts, origins, res))
    if not parts:
        return Grid(np.zeros((0, 4)), np.zeros(0, np.int64), 0)
    keys = np.concatenate([p[0] for p in parts])
    sums = np.concatenate([p[1] for p in parts])
    counts = np.concatenate([p[2] for p in parts])
    if len(parts) > 1:  # merge the cells that several chunks share
        keys, inverse = np.unique(keys, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        merged = np.zeros((len(keys), 4))
        np.add.at(merged, inverse, sums)
        sums, counts = merged, np.bincount(inverse, weights=counts, minlength=len(keys)).astype(np.int64)
    return Grid(means=sums / counts[:, None], counts=counts, returns=total)

