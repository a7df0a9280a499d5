"""Projecting scans and clouds: every beam into the world frame with the robot's pose at the moment it
was measured, accumulated per grid cell (memory for the grid, not for every return), and free space
carved along every beam (occupancy.py)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .occupancy import LogOdds
from .reading import BagData
from .scans import ScanBatch


def poses_at(data: BagData, t: np.ndarray) -> np.ndarray:
    """The robot's poses (..., 3) x, y, yaw in the world frame at times ``t`` (any shape), interpolated."""
    od = data.odom
    yaw = np.unwrap(od[:, 3])
    flat = np.asarray(t, dtype=float).reshape(-1)
    out = np.stack([np.interp(flat, od[:, 0], od[:, 1]), np.interp(flat, od[:, 0], od[:, 2]),
                    np.interp(flat, od[:, 0], yaw)], axis=1)
    return out.reshape(np.shape(t) + (3,))


@dataclass
class Rays:
    """The beams of a batch of scans in the world frame, each placed with the robot's pose at its own
    time (the scan's timing): laser position ``ox``, ``oy``, direction ``angle`` (rad), ``range``
    (m) and whether it is a return (``valid``) or saw nothing within ``range_max`` (``none``);
    all (scans, beams)."""
    ox: np.ndarray
    oy: np.ndarray
    angle: np.ndarray
    range: np.ndarray
    valid: np.ndarray
    none: np.ndarray
    t: np.ndarray          # (scans, beams) or (scans, 1): when each beam was measured


def beam_rays(data: BagData, batch: ScanBatch, mount: tuple[float, float, float], timing=None) -> Rays:
    """Each beam of ``batch`` from where the laser was when it measured it (de-skewed, as
    laser_geometry's transformLaserScanToPointCloud does with ``time_increment``); ``timing``:
    another reading of the scans' timing than ``data.scan_timing``."""
    layout = data.scan_layout
    timing = data.scan_timing if timing is None else timing
    rng = batch.ranges
    valid = np.isfinite(rng) & (rng > layout.range_min) & (rng < layout.range_max * 0.99)
    none = (rng >= layout.range_max * 0.99) & ~np.isnan(rng)      # +inf or range_max: nothing seen
    if timing.skewed:
        t = batch.t[:, None] + timing.beam_offsets(layout.beams)[None, :]
    else:
        t = (batch.t + timing.offset)[:, None]
    poses = poses_at(data, t)
    px, py, pyaw = poses[..., 0], poses[..., 1], poses[..., 2]
    mx, my, myaw = mount
    c, s = np.cos(pyaw), np.sin(pyaw)
    shape = rng.shape
    return Rays(ox=np.broadcast_to(px + c * mx - s * my, shape), oy=np.broadcast_to(py + s * mx + c * my, shape),
                angle=pyaw + myaw + layout.angles[None, :], range=rng, valid=valid, none=none, t=t)


def project_scans(data: BagData, batch: ScanBatch, mount: tuple[float, float, float],
                  timing=None) -> tuple[np.ndarray, np.ndarray]:
    """Every valid return of ``batch`` as a point in the world frame, and the laser position it was seen from."""
    r = beam_rays(data, batch, mount, timing)
    rng = r.range[r.valid].astype(float)
    ang = r.angle[r.valid]
    ox, oy = r.ox[r.valid], r.oy[r.valid]
    return np.stack([ox + rng * np.cos(ang), oy + rng * np.sin(ang)], 1), np.stack([ox, oy], 1)


def cell_count(points: np.ndarray, res: float) -> int:
    """How many cells of ``res`` the points fall in (fewer: a sharper map)."""
    if not len(points):
        return 0
    cells = np.floor(points / res).astype(np.int64)
    cells -= cells.min(axis=0)
    span = cells.max(axis=0) + 1
    if span[0] * span[1] <= 4_000_000:   # a dense count is several times faster than np.unique
        return int(np.count_nonzero(np.bincount(cells[:, 1] * span[0] + cells[:, 0])))
    return len(np.unique(cells[:, 0] * 1_000_003 + cells[:, 1]))


SHARPER = 0.02    # another reading of the scans' timing must make the map this much sharper to be used


def settle_timing(data: BagData, mount: tuple[float, float, float], sample: ScanBatch | None = None,
                  res: float = 0.02) -> None:
    """When the scans' fields and the bag's receive times leave the timing open (time_increment 0
    with a scan_time; receive times that do not tell the stamp's convention), keep the reading that
    makes the map of a sample of scans sharpest (fewest cells), the default unless another is
    SHARPER; say which in ``data.scan_timing.how``."""
    import dataclasses

    from .streaming import sample_scans

    timing = data.scan_timing
    if not timing.alternatives:
        return
    part = sample if sample is not None else sample_scans(data)
    readings = [timing, *timing.alternatives]
    counts = [cell_count(project_scans(data, part, mount, t)[0], res) for t in readings]
    best = int(np.argmin(counts))
    if best and counts[best] > (1 - SHARPER) * counts[0]:
        best = 0
    chosen = readings[best]
    others = ", ".join(f"{c} for {'the default' if i == 0 else 'the alternative ' + str(i)}"
                       for i, c in enumerate(counts) if i != best)
    data.scan_timing = dataclasses.replace(
        chosen, alternatives=(), warnings=timing.warnings,
        how=f"{chosen.how} (the sharpest map of {len(part.t)} scans: {counts[best]} cells of {res * 100:g} cm, "
            f"against {others})")


@dataclass
class Grid:
    """Returns accumulated per grid cell: the cell's mean return and mean viewpoint, and hits;
    for 3D returns also the highest point above the ground seen in the cell (NaN for 2D scans)."""
    means: np.ndarray    # (k, 4) x, y of the returns, x, y of the laser that saw them
    counts: np.ndarray   # (k,) returns per cell
    returns: int         # returns in total
    top: np.ndarray | None = None   # (k,) m above the ground, or None (2D scans)
    keys: np.ndarray | None = None  # (k,) the cells as GridAccumulator keys (column * 2^32 + row)

    @property
    def cells(self) -> np.ndarray:
        """(k, 2) column, row of each cell (floor of the coordinates over the cell size)."""
        keys = np.zeros(0, np.int64) if self.keys is None else self.keys
        row = (keys + 2**31) % 2**32 - 2**31
        return np.stack([(keys - row) // 2**32, row], 1)


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
        keys, sums, counts, top = self._merged()
        return Grid(means=sums / counts[:, None], counts=counts, returns=self.returns,
                    top=np.where(np.isfinite(top), top, np.nan) if self.has_height else None, keys=keys)


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


@dataclass
class ScanMap:
    """What the streamed pass over the scans built: the returns per cell (``grid``), the log-odds
    occupancy with free space carved by every beam (``occupancy``), a sample of the scans for the
    fit figure, the first scan of the window, and how far the robot moved within one scan."""
    grid: Grid
    occupancy: LogOdds
    sample: ScanBatch
    first: ScanBatch
    scans: int
    skew: tuple[float, float] = (0.0, 0.0)   # largest motion within one scan: metres, degrees


def map_scans(data: BagData, mount: tuple[float, float, float], res: float = 0.05,
              sample: int = 100) -> ScanMap:
    """Stream the window's scans (scans.stream_scans), each beam placed at its own time, into a grid
    of returns and a log-odds occupancy grid (memory for the area seen, not the bag's length); keep
    about ``sample`` scans spread over the window (and the first) for the fit figure."""
    from .occupancy import LogOdds, reach_of
    from .streaming import stream_scans

    layout = data.scan_layout
    reach = reach_of(layout.range_max)
    od = data.odom[:, 1:3]
    pad = reach + math.hypot(mount[0], mount[1]) + 2 * res
    occ = LogOdds(od.min(axis=0) - pad, od.max(axis=0) + pad, res)
    acc = GridAccumulator(res)
    t0, t1 = data.odom[0, 0], data.odom[-1, 0]
    received = data.scan_received
    expected = max(1, int(np.count_nonzero((received >= data.origin_ns + (t0 - 1) * 1e9)
                                           & (received <= data.origin_ns + (t1 + 1) * 1e9))))
    every = max(1, expected // sample)
    kept_t: list[np.ndarray] = []
    kept_r: list[np.ndarray] = []
    first = None
    count, skew_m, skew_deg = 0, 0.0, 0.0
    for batch in stream_scans(data):
        rays = beam_rays(data, batch, mount)
        keep = rays.valid & (rays.range <= reach)
        rng = rays.range[keep].astype(float)
        ang = rays.angle[keep]
        ox, oy = rays.ox[keep], rays.oy[keep]
        acc.add(np.stack([ox + rng * np.cos(ang), oy + rng * np.sin(ang)], 1), np.stack([ox, oy], 1))
        occ.add_rays(rays, reach)
        if first is None:
            first = ScanBatch(batch.t[:1].copy(), batch.ranges[:1].copy())
        pick = (count + np.arange(len(batch.t))) % every == 0
        kept_t.append(batch.t[pick])
        kept_r.append(batch.ranges[pick])
        count += len(batch.t)
        if data.scan_timing.skewed:
            moved = np.hypot(rays.ox[:, -1] - rays.ox[:, 0], rays.oy[:, -1] - rays.oy[:, 0])
            turned = np.abs(rays.angle[:, -1] - rays.angle[:, 0] - (layout.angles[-1] - layout.angles[0]))
            skew_m, skew_deg = max(skew_m, float(moved.max())), max(skew_deg, math.degrees(float(turned.max())))
    empty = ScanBatch(np.zeros(0), np.zeros((0, layout.beams), np.float32))
    smp = ScanBatch(np.concatenate(kept_t), np.concatenate(kept_r)) if kept_t else empty
    return ScanMap(grid=acc.grid(), occupancy=occ, sample=smp, first=first or empty, scans=count,
                   skew=(skew_m, skew_deg))
